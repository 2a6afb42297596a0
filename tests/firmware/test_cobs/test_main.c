/*
 * Unity tests of rw_cobs (the USB serial framing): known encodings (empty, zeros only, zero runs,
 * no zero), round trips of zero runs and of 253/254/255/508-byte zero-free blocks, no zero byte in any
 * encoding, the size bound RW_COBS_MAX_ENCODED, and malformed input (a zero inside, a code running past
 * the end, empty input, an output buffer too small) decoded to 0. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_cobs.h"

#define BIG 600u

static uint8_t in[BIG];
static uint8_t enc[RW_COBS_MAX_ENCODED(BIG)];
static uint8_t dec[BIG];

void setUp(void)
{
    memset(in, 0, sizeof in);
    memset(enc, 0xEE, sizeof enc);
    memset(dec, 0xEE, sizeof dec);
}

void tearDown(void) {}

/* Encodes n bytes of `in`, checks the encoding holds no zero and fits the bound, decodes it back and
 * checks the bytes; returns the encoded length. */
static size_t round_trip(size_t n)
{
    size_t e = rw_cobs_encode(in, n, enc, sizeof enc);
    TEST_ASSERT_TRUE_MESSAGE(e >= n + 1u && e <= RW_COBS_MAX_ENCODED(n), "encoded size within n+1..bound");
    for (size_t i = 0u; i < e; ++i) {
        TEST_ASSERT_NOT_EQUAL_MESSAGE(0u, enc[i], "no zero byte in an encoding");
    }
    size_t d = rw_cobs_decode(enc, e, dec, sizeof dec);
    TEST_ASSERT_EQUAL_UINT(n, d);
    if (n > 0u) {
        TEST_ASSERT_EQUAL_UINT8_ARRAY(in, dec, n);
    }
    return e;
}

static void check_encoding(const uint8_t *data, size_t n, const uint8_t *expected, size_t expected_len)
{
    memcpy(in, data, n);
    TEST_ASSERT_EQUAL_UINT(expected_len, rw_cobs_encode(in, n, enc, sizeof enc));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(expected, enc, expected_len);
}

static void test_known_encodings(void)
{
    static const uint8_t zero1[] = { 0x00 }, zero1_e[] = { 0x01, 0x01 };
    static const uint8_t zero2[] = { 0x00, 0x00 }, zero2_e[] = { 0x01, 0x01, 0x01 };
    static const uint8_t mid[] = { 0x11, 0x22, 0x00, 0x33 }, mid_e[] = { 0x03, 0x11, 0x22, 0x02, 0x33 };
    static const uint8_t none[] = { 0x11, 0x22, 0x33, 0x44 }, none_e[] = { 0x05, 0x11, 0x22, 0x33, 0x44 };
    static const uint8_t tail[] = { 0x11, 0x00, 0x00, 0x00 }, tail_e[] = { 0x02, 0x11, 0x01, 0x01, 0x01 };
    static const uint8_t empty_e[] = { 0x01 };
    check_encoding(zero1, 0u, empty_e, 1u);
    check_encoding(zero1, sizeof zero1, zero1_e, sizeof zero1_e);
    check_encoding(zero2, sizeof zero2, zero2_e, sizeof zero2_e);
    check_encoding(mid, sizeof mid, mid_e, sizeof mid_e);
    check_encoding(none, sizeof none, none_e, sizeof none_e);
    check_encoding(tail, sizeof tail, tail_e, sizeof tail_e);
}

static void test_round_trips_with_zero_runs(void)
{
    for (size_t n = 1u; n <= 40u; ++n) { /* all zeros */
        TEST_ASSERT_EQUAL_UINT(n + 1u, round_trip(n));
    }
    for (size_t i = 0u; i < 300u; ++i) { /* runs of 0..4 zeros between 1..6 non-zero bytes */
        in[i] = (i % 11u) < 4u ? 0u : (uint8_t)(1u + i % 251u);
    }
    round_trip(300u);
    in[0] = 0u;
    in[299] = 0u;
    round_trip(300u);
}

/* A zero-free block of 254 bytes is the longest one code byte covers (0xFF: no zero follows). */
static void test_254_and_255_byte_blocks(void)
{
    const size_t lengths[] = { 253u, 254u, 255u, 508u, 509u, BIG };
    for (unsigned k = 0u; k < sizeof lengths / sizeof lengths[0]; ++k) {
        for (size_t i = 0u; i < lengths[k]; ++i) {
            in[i] = (uint8_t)(1u + i % 255u);
        }
        round_trip(lengths[k]);
        if (lengths[k] >= 254u) {
            TEST_ASSERT_EQUAL_HEX8_MESSAGE(0xFFu, enc[0], "a full block's code");
            TEST_ASSERT_EQUAL_UINT8(in[253], enc[254]);
        }
    }
    /* a full block, then a zero: the zero starts the next block */
    for (size_t i = 0u; i < 254u; ++i) {
        in[i] = 0x5Au;
    }
    in[254] = 0u;
    in[255] = 0x33u;
    round_trip(256u);
    TEST_ASSERT_EQUAL_HEX8(0xFFu, enc[0]);
    TEST_ASSERT_EQUAL_HEX8(0x01u, enc[255]); /* the zero right after the full block */
    TEST_ASSERT_EQUAL_HEX8(0x02u, enc[256]);
}

static void test_malformed_input_decodes_to_zero(void)
{
    static const uint8_t zero_inside[] = { 0x03, 0x11, 0x00, 0x02, 0x33 };
    static const uint8_t past_end[] = { 0x05, 0x11, 0x22 };
    static const uint8_t past_end_later[] = { 0x02, 0x11, 0x04, 0x22 };
    static const uint8_t zero_code[] = { 0x00, 0x11 };
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(zero_inside, sizeof zero_inside, dec, sizeof dec));
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(past_end, sizeof past_end, dec, sizeof dec));
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(past_end_later, sizeof past_end_later, dec, sizeof dec));
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(zero_code, sizeof zero_code, dec, sizeof dec));
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(zero_code, 0u, dec, sizeof dec));
}

static void test_buffers_too_small_give_zero(void)
{
    static const uint8_t data[] = { 0x11, 0x22, 0x00, 0x33 };
    uint8_t small[8];
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_encode(data, sizeof data, small, RW_COBS_MAX_ENCODED(sizeof data) - 1u));
    size_t e = rw_cobs_encode(data, sizeof data, small, sizeof small);
    TEST_ASSERT_EQUAL_UINT(5u, e);
    TEST_ASSERT_EQUAL_UINT(0u, rw_cobs_decode(small, e, dec, 3u)); /* 4 bytes do not fit in 3 */
    TEST_ASSERT_EQUAL_UINT(4u, rw_cobs_decode(small, e, dec, 4u));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(data, dec, 4u);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_known_encodings);
    RUN_TEST(test_round_trips_with_zero_runs);
    RUN_TEST(test_254_and_255_byte_blocks);
    RUN_TEST(test_malformed_input_decodes_to_zero);
    RUN_TEST(test_buffers_too_small_give_zero);
    return UNITY_END();
}
