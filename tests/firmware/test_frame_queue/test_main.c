/*
 * Unity tests of rw_frame_queue, the frames between the board's control tick and its background loop: FIFO
 * with addresses kept, a full queue refuses and counts, an oversize frame is marked, reserve/publish in place,
 * indices wrap. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_frame_queue.h"

static rw_frame_queue q;

void setUp(void)
{
    rw_frame_queue_init(&q);
}

void tearDown(void) {}

static void test_fifo_with_addresses(void)
{
    for (uint8_t i = 0u; i < RW_FRAME_QUEUE_SLOTS; ++i) {
        const uint8_t frame[2] = { i, (uint8_t)(i + 1u) };
        TEST_ASSERT_TRUE(rw_frame_queue_push(&q, frame, sizeof frame, 100u + i, (uint16_t)(200u + i)));
    }
    for (uint8_t i = 0u; i < RW_FRAME_QUEUE_SLOTS; ++i) {
        const rw_frame_queue_slot *s = rw_frame_queue_peek(&q);
        TEST_ASSERT_NOT_NULL(s);
        TEST_ASSERT_EQUAL_UINT8(i, s->bytes[0]);
        TEST_ASSERT_EQUAL_UINT16(2u, s->len);
        TEST_ASSERT_EQUAL_UINT32(100u + i, s->addr);
        TEST_ASSERT_EQUAL_UINT16(200u + i, s->port);
        rw_frame_queue_release(&q);
    }
    TEST_ASSERT_NULL(rw_frame_queue_peek(&q));
}

static void test_full_queue_refuses_and_counts(void)
{
    const uint8_t frame[1] = { 1u };
    for (unsigned i = 0u; i < RW_FRAME_QUEUE_SLOTS; ++i) {
        TEST_ASSERT_TRUE(rw_frame_queue_push(&q, frame, 1u, 0u, 0u));
    }
    TEST_ASSERT_FALSE(rw_frame_queue_push(&q, frame, 1u, 0u, 0u));
    TEST_ASSERT_NULL(rw_frame_queue_reserve(&q));
    TEST_ASSERT_EQUAL_UINT32(2u, q.dropped);
    TEST_ASSERT_EQUAL_UINT32(RW_FRAME_QUEUE_SLOTS, q.high_water);
    rw_frame_queue_release(&q);
    TEST_ASSERT_TRUE(rw_frame_queue_push(&q, frame, 1u, 0u, 0u));
}

static void test_oversize_is_marked(void)
{
    uint8_t big[RW_MAX_FRAME_LEN + 10u];
    memset(big, 0x5A, sizeof big);
    TEST_ASSERT_TRUE(rw_frame_queue_push(&q, big, sizeof big, 0u, 0u));
    TEST_ASSERT_EQUAL_UINT16(RW_FRAME_QUEUE_OVERSIZE, rw_frame_queue_peek(&q)->len);
    TEST_ASSERT_EQUAL_UINT32(1u, q.oversize);
}

static void test_reserve_publish_in_place(void)
{
    rw_frame_queue_slot *s = rw_frame_queue_reserve(&q);
    TEST_ASSERT_NOT_NULL(s);
    s->bytes[0] = 0xAAu;
    s->len = 1u;
    TEST_ASSERT_NULL(rw_frame_queue_peek(&q));
    rw_frame_queue_publish(&q);
    TEST_ASSERT_EQUAL_UINT8(0xAAu, rw_frame_queue_peek(&q)->bytes[0]);
}

static void test_indices_wrap(void)
{
    q.head = q.tail = 0xFFFFFFFEu;
    for (uint8_t i = 0u; i < 3u * RW_FRAME_QUEUE_SLOTS; ++i) {
        TEST_ASSERT_TRUE(rw_frame_queue_push(&q, &i, 1u, 0u, 0u));
        TEST_ASSERT_EQUAL_UINT32(1u, rw_frame_queue_count(&q));
        TEST_ASSERT_EQUAL_UINT8(i, rw_frame_queue_peek(&q)->bytes[0]);
        rw_frame_queue_release(&q);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_fifo_with_addresses);
    RUN_TEST(test_full_queue_refuses_and_counts);
    RUN_TEST(test_oversize_is_marked);
    RUN_TEST(test_reserve_publish_in_place);
    RUN_TEST(test_indices_wrap);
    return UNITY_END();
}
