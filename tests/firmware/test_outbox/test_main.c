/*
 * Unity tests of rw_outbox: replies before events before telemetry, oldest first within a class;
 * when full, a new telemetry frame is dropped, a reply or event displaces the oldest telemetry, and
 * nothing displaces a reply or an event; drops are counted. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_outbox.h"

static rw_outbox box;

void setUp(void)
{
    rw_outbox_reset(&box);
}

void tearDown(void) {}

/* A frame whose bytes say which class and number it is: [cls, n, n, ...] (len 3 + n % 5). */
static void push_tagged(rw_outbox_class cls, uint8_t n, bool expect_ok)
{
    uint8_t frame[16];
    size_t len = 3u + (size_t)(n % 5u);
    memset(frame, n, sizeof frame);
    frame[0] = (uint8_t)cls;
    TEST_ASSERT_EQUAL(expect_ok, rw_outbox_push(&box, cls, frame, len));
}

/* Pops the next frame and checks its class and number. */
static void pop_expect(rw_outbox_class cls, uint8_t n)
{
    const rw_outbox_slot *s = rw_outbox_peek(&box);
    TEST_ASSERT_NOT_NULL(s);
    TEST_ASSERT_EQUAL_UINT8((uint8_t)cls, s->bytes[0]);
    TEST_ASSERT_EQUAL_UINT8(n, s->bytes[1]);
    TEST_ASSERT_EQUAL_UINT8(3u + n % 5u, s->len);
    rw_outbox_pop(&box, s);
}

static void test_empty_outbox_has_nothing_to_send(void)
{
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_outbox_dropped(&box));
}

static void test_priority_reply_event_telemetry_then_age(void)
{
    push_tagged(RW_OUTBOX_TELEMETRY, 1u, true);
    push_tagged(RW_OUTBOX_EVENT, 2u, true);
    push_tagged(RW_OUTBOX_TELEMETRY, 3u, true);
    push_tagged(RW_OUTBOX_REPLY, 4u, true);
    push_tagged(RW_OUTBOX_EVENT, 5u, true);
    pop_expect(RW_OUTBOX_REPLY, 4u);
    pop_expect(RW_OUTBOX_EVENT, 2u);
    pop_expect(RW_OUTBOX_EVENT, 5u);
    pop_expect(RW_OUTBOX_TELEMETRY, 1u);
    pop_expect(RW_OUTBOX_TELEMETRY, 3u);
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_outbox_dropped(&box));
}

static void test_full_of_telemetry_new_telemetry_is_dropped(void)
{
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged(RW_OUTBOX_TELEMETRY, i, true);
    }
    push_tagged(RW_OUTBOX_TELEMETRY, 99u, false);
    TEST_ASSERT_EQUAL_UINT16(1u, rw_outbox_dropped(&box));
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        pop_expect(RW_OUTBOX_TELEMETRY, i);
    }
}

static void test_event_and_reply_displace_the_oldest_telemetry(void)
{
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged(RW_OUTBOX_TELEMETRY, i, true);
    }
    push_tagged(RW_OUTBOX_EVENT, 50u, true);
    push_tagged(RW_OUTBOX_REPLY, 51u, true);
    TEST_ASSERT_EQUAL_UINT16(2u, rw_outbox_dropped(&box));
    pop_expect(RW_OUTBOX_REPLY, 51u);
    pop_expect(RW_OUTBOX_EVENT, 50u);
    for (uint8_t i = 2u; i < RW_OUTBOX_SLOTS; ++i) {
        pop_expect(RW_OUTBOX_TELEMETRY, i);
    }
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
}

static void test_nothing_displaces_events_or_replies(void)
{
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged((i % 2u) != 0u ? RW_OUTBOX_EVENT : RW_OUTBOX_REPLY, i, true);
    }
    push_tagged(RW_OUTBOX_TELEMETRY, 60u, false);
    push_tagged(RW_OUTBOX_EVENT, 61u, false);
    push_tagged(RW_OUTBOX_REPLY, 62u, false);
    TEST_ASSERT_EQUAL_UINT16(3u, rw_outbox_dropped(&box));
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; i += 2u) {
        pop_expect(RW_OUTBOX_REPLY, i);
    }
    for (uint8_t i = 1u; i < RW_OUTBOX_SLOTS; i += 2u) {
        pop_expect(RW_OUTBOX_EVENT, i);
    }
}

static void test_a_popped_slot_is_reused(void)
{
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged(RW_OUTBOX_EVENT, i, true);
    }
    pop_expect(RW_OUTBOX_EVENT, 0u);
    push_tagged(RW_OUTBOX_TELEMETRY, 70u, true);
    push_tagged(RW_OUTBOX_TELEMETRY, 71u, false);
    for (uint8_t i = 1u; i < RW_OUTBOX_SLOTS; ++i) {
        pop_expect(RW_OUTBOX_EVENT, i);
    }
    pop_expect(RW_OUTBOX_TELEMETRY, 70u);
}

static void test_empty_or_oversized_frames_are_refused(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN + 1u];
    memset(frame, 0xB7, sizeof frame);
    TEST_ASSERT_FALSE(rw_outbox_push(&box, RW_OUTBOX_EVENT, frame, 0u));
    TEST_ASSERT_FALSE(rw_outbox_push(&box, RW_OUTBOX_EVENT, frame, RW_MAX_FRAME_LEN + 1u));
    TEST_ASSERT_EQUAL_UINT16(2u, rw_outbox_dropped(&box));
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
    TEST_ASSERT_TRUE(rw_outbox_push(&box, RW_OUTBOX_EVENT, frame, RW_MAX_FRAME_LEN));
    const rw_outbox_slot *s = rw_outbox_peek(&box);
    TEST_ASSERT_NOT_NULL(s);
    TEST_ASSERT_EQUAL_UINT8(RW_MAX_FRAME_LEN, s->len);
    TEST_ASSERT_EQUAL_MEMORY(frame, s->bytes, RW_MAX_FRAME_LEN);
}

/* Encoding in place: reserve + write + commit queues exactly like a push; a full outbox refuses the
 * reservation (a drop), a failed encode (length 0) frees the slot again; an empty outbox is cheap to peek
 * and stays empty after every slot is popped. */
static void test_reserve_and_commit_queue_like_a_push(void)
{
    push_tagged(RW_OUTBOX_EVENT, 1u, true);
    rw_outbox_slot *slot = rw_outbox_reserve(&box, RW_OUTBOX_TELEMETRY);
    TEST_ASSERT_NOT_NULL(slot);
    memset(slot->bytes, 2u, 5u);
    slot->bytes[0] = (uint8_t)RW_OUTBOX_TELEMETRY;
    TEST_ASSERT_TRUE(rw_outbox_commit(&box, slot, RW_OUTBOX_TELEMETRY, 5u));
    slot = rw_outbox_reserve(&box, RW_OUTBOX_TELEMETRY);
    TEST_ASSERT_FALSE(rw_outbox_commit(&box, slot, RW_OUTBOX_TELEMETRY, 0u)); /* encode failed */
    TEST_ASSERT_EQUAL_UINT16(1u, rw_outbox_dropped(&box));
    pop_expect(RW_OUTBOX_EVENT, 1u);
    pop_expect(RW_OUTBOX_TELEMETRY, 2u);
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged(RW_OUTBOX_REPLY, i, true);
    }
    TEST_ASSERT_NULL(rw_outbox_reserve(&box, RW_OUTBOX_TELEMETRY));
    TEST_ASSERT_EQUAL_UINT16(2u, rw_outbox_dropped(&box));
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        pop_expect(RW_OUTBOX_REPLY, i);
    }
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
}

/* A telemetry slot displaced by an event whose encode then fails is gone, not sent half-overwritten. */
static void test_failed_commit_over_displaced_telemetry_frees_the_slot(void)
{
    for (uint8_t i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        push_tagged(RW_OUTBOX_TELEMETRY, i, true);
    }
    rw_outbox_slot *slot = rw_outbox_reserve(&box, RW_OUTBOX_EVENT);
    TEST_ASSERT_NOT_NULL(slot);
    memset(slot->bytes, 0xEE, 4u);
    TEST_ASSERT_FALSE(rw_outbox_commit(&box, slot, RW_OUTBOX_EVENT, 0u));
    for (uint8_t i = 1u; i < RW_OUTBOX_SLOTS; ++i) {
        pop_expect(RW_OUTBOX_TELEMETRY, i);
    }
    TEST_ASSERT_NULL(rw_outbox_peek(&box));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_reserve_and_commit_queue_like_a_push);
    RUN_TEST(test_failed_commit_over_displaced_telemetry_frees_the_slot);
    RUN_TEST(test_empty_outbox_has_nothing_to_send);
    RUN_TEST(test_priority_reply_event_telemetry_then_age);
    RUN_TEST(test_full_of_telemetry_new_telemetry_is_dropped);
    RUN_TEST(test_event_and_reply_displace_the_oldest_telemetry);
    RUN_TEST(test_nothing_displaces_events_or_replies);
    RUN_TEST(test_a_popped_slot_is_reused);
    RUN_TEST(test_empty_or_oversized_frames_are_refused);
    return UNITY_END();
}
