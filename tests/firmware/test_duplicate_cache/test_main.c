/*
 * Unity tests of rw_duplicate_cache: a command seen within RW_DUPLICATE_WINDOW_MS (same msg_id, seq
 * and checksum) is found with its verdict; other seq/checksum/msg_id is new; the window is wrap-safe;
 * the ring keeps the last RW_DUPLICATE_CACHE_SIZE commands. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <unity.h>

#include "rw_duplicate_cache.h"
#include "rw_protocol.h"

static rw_duplicate_cache cache;

void setUp(void)
{
    rw_duplicate_cache_reset(&cache);
}

void tearDown(void) {}

static void test_empty_cache_finds_nothing(void)
{
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_ARM, 0u, 0u, 0u));
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_ARM, 1u, 0x1234u, 100u));
}

static void test_stored_command_is_found_with_its_verdict(void)
{
    rw_duplicate_cache_store(&cache, RW_MSG_ID_SET_ROPE_SPEED, 42u, 0xBEEFu, RW_NACK_REASON_OUT_OF_RANGE, 20000, 1000u);
    const rw_duplicate_entry *e = rw_duplicate_cache_find(&cache, RW_MSG_ID_SET_ROPE_SPEED, 42u, 0xBEEFu, 1500u);
    TEST_ASSERT_NOT_NULL(e);
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, e->nack_reason);
    TEST_ASSERT_EQUAL_INT32(20000, e->nack_detail);
    rw_duplicate_cache_store(&cache, RW_MSG_ID_ARM, 43u, 0x0101u, 0u, 0, 1600u);
    e = rw_duplicate_cache_find(&cache, RW_MSG_ID_ARM, 43u, 0x0101u, 1600u);
    TEST_ASSERT_NOT_NULL(e);
    TEST_ASSERT_EQUAL_UINT8(0u, e->nack_reason);
}

static void test_other_seq_checksum_or_message_is_a_new_command(void)
{
    rw_duplicate_cache_store(&cache, RW_MSG_ID_PARAM_SET, 7u, 0xAAAAu, 0u, 0, 0u);
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_SET, 7u, 0xAAABu, 1u)); /* same seq, other bytes */
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_SET, 8u, 0xAAAAu, 1u));
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_GET, 7u, 0xAAAAu, 1u));
    TEST_ASSERT_NOT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_SET, 7u, 0xAAAAu, 1u));
}

static void test_window_ends_after_window_ms(void)
{
    rw_duplicate_cache_store(&cache, RW_MSG_ID_ESTOP, 9u, 0x1111u, 0u, 0, 2000u);
    TEST_ASSERT_NOT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_ESTOP, 9u, 0x1111u, 2000u + RW_DUPLICATE_WINDOW_MS));
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_ESTOP, 9u, 0x1111u, 2000u + RW_DUPLICATE_WINDOW_MS + 1u));
}

static void test_window_is_wrap_safe(void)
{
    const uint32_t t0 = 0xFFFFFF00u;
    rw_duplicate_cache_store(&cache, RW_MSG_ID_SPINDOWN, 3u, 0x2222u, 0u, 0, t0);
    TEST_ASSERT_NOT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_SPINDOWN, 3u, 0x2222u, t0 + 1000u)); /* wrapped */
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_SPINDOWN, 3u, 0x2222u, t0 + RW_DUPLICATE_WINDOW_MS + 1u));
}

static void test_ring_keeps_the_last_entries(void)
{
    for (uint16_t seq = 0u; seq < RW_DUPLICATE_CACHE_SIZE + 3u; ++seq) {
        rw_duplicate_cache_store(&cache, RW_MSG_ID_PARAM_GET, seq, (uint16_t)(0x100u + seq), 0u, 0, 10u);
    }
    for (uint16_t seq = 0u; seq < 3u; ++seq) {
        TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_GET, seq, (uint16_t)(0x100u + seq), 10u));
    }
    for (uint16_t seq = 3u; seq < RW_DUPLICATE_CACHE_SIZE + 3u; ++seq) {
        TEST_ASSERT_NOT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_PARAM_GET, seq, (uint16_t)(0x100u + seq), 10u));
    }
}

static void test_reset_forgets_everything(void)
{
    rw_duplicate_cache_store(&cache, RW_MSG_ID_ARM, 1u, 0x3333u, 0u, 0, 5u);
    rw_duplicate_cache_reset(&cache);
    TEST_ASSERT_NULL(rw_duplicate_cache_find(&cache, RW_MSG_ID_ARM, 1u, 0x3333u, 5u));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_empty_cache_finds_nothing);
    RUN_TEST(test_stored_command_is_found_with_its_verdict);
    RUN_TEST(test_other_seq_checksum_or_message_is_a_new_command);
    RUN_TEST(test_window_ends_after_window_ms);
    RUN_TEST(test_window_is_wrap_safe);
    RUN_TEST(test_ring_keeps_the_last_entries);
    RUN_TEST(test_reset_forgets_everything);
    return UNITY_END();
}
