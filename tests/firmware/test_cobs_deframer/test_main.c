/*
 * Unity tests of rw_cobs_deframer (the serial HALs' receive side): frames split over any chunking, several
 * frames in one stream, back-to-back delimiters skipped, malformed COBS and over-long runs handed on as one
 * 0x00 byte ("not a frame", which the core NACKs) and counted, resynchronisation at the next delimiter, and
 * a frame too large for the caller's buffer. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_cobs_deframer.h"
#include "rw_protocol.h"

static rw_cobs_deframer d;
static uint8_t out[RW_MAX_FRAME_LEN];

void setUp(void)
{
    rw_cobs_deframer_reset(&d);
    memset(out, 0xEE, sizeof out);
}

void tearDown(void) {}

/* Feeds bytes; returns the length of the first completed frame (0 if none) and how many bytes that took. */
static size_t feed(const uint8_t *bytes, size_t n, size_t *used)
{
    for (size_t i = 0u; i < n; ++i) {
        const size_t len = rw_cobs_deframer_put(&d, bytes[i], out, sizeof out);
        if (len != 0u) {
            *used = i + 1u;
            return len;
        }
    }
    *used = n;
    return 0u;
}

/* COBS encoding of frame plus the delimiter into wire; its length. */
static size_t wire_of(const uint8_t *frame, size_t n, uint8_t *wire, size_t cap)
{
    const size_t e = rw_cobs_encode(frame, n, wire, cap - 1u);
    TEST_ASSERT_NOT_EQUAL(0u, e);
    wire[e] = 0u;
    return e + 1u;
}

static void test_one_frame_byte_by_byte_then_nothing_more(void)
{
    static const uint8_t frame[] = { 0xB7, 0x02, 0x00, 0x10, 0x00, 0x00, 0x01, 0x00, 0x42 };
    uint8_t wire[32];
    const size_t n = wire_of(frame, sizeof frame, wire, sizeof wire);
    size_t used = 0u;
    TEST_ASSERT_EQUAL_UINT(sizeof frame, feed(wire, n, &used));
    TEST_ASSERT_EQUAL_UINT(n, used); /* complete exactly at the delimiter */
    TEST_ASSERT_EQUAL_UINT8_ARRAY(frame, out, sizeof frame);
    TEST_ASSERT_EQUAL_UINT32(1u, rw_cobs_deframer_frames(&d));
    TEST_ASSERT_EQUAL_UINT32(0u, rw_cobs_deframer_bad_frames(&d));
}

static void test_two_frames_in_one_stream_and_empty_delimiters_skipped(void)
{
    static const uint8_t a[] = { 1, 2, 3 };
    static const uint8_t b[] = { 0, 0, 9 };
    uint8_t wire[32];
    size_t n = 0u;
    wire[n++] = 0u; /* a leading delimiter (a host resynchronising) */
    n += wire_of(a, sizeof a, wire + n, sizeof wire - n);
    wire[n++] = 0u;
    wire[n++] = 0u;
    n += wire_of(b, sizeof b, wire + n, sizeof wire - n);
    size_t used = 0u;
    TEST_ASSERT_EQUAL_UINT(sizeof a, feed(wire, n, &used));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(a, out, sizeof a);
    size_t used2 = 0u;
    TEST_ASSERT_EQUAL_UINT(sizeof b, feed(wire + used, n - used, &used2));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(b, out, sizeof b);
    TEST_ASSERT_EQUAL_UINT(n, used + used2);
    TEST_ASSERT_EQUAL_UINT32(2u, rw_cobs_deframer_frames(&d));
    TEST_ASSERT_EQUAL_UINT32(0u, rw_cobs_deframer_bad_frames(&d));
}

static void test_malformed_cobs_is_handed_on_as_not_a_frame_then_resync(void)
{
    static const uint8_t bad[] = { 0x05, 0x11, 0x22, 0x00 }; /* the code runs past the delimiter */
    static const uint8_t good[] = { 0x33, 0x44 };
    size_t used = 0u;
    TEST_ASSERT_EQUAL_UINT(1u, feed(bad, sizeof bad, &used));
    TEST_ASSERT_EQUAL_UINT8(0u, out[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, rw_cobs_deframer_bad_frames(&d));
    uint8_t wire[8];
    const size_t n = wire_of(good, sizeof good, wire, sizeof wire);
    TEST_ASSERT_EQUAL_UINT(sizeof good, feed(wire, n, &used));
    TEST_ASSERT_EQUAL_UINT8_ARRAY(good, out, sizeof good);
}

static void test_an_over_long_run_is_one_bad_frame_at_its_delimiter(void)
{
    size_t used = 0u;
    for (unsigned i = 0u; i < RW_COBS_DEFRAMER_MAX_ENCODED + 50u; ++i) {
        const uint8_t byte = 0x7Fu;
        TEST_ASSERT_EQUAL_UINT(0u, feed(&byte, 1u, &used));
    }
    const uint8_t delimiter = 0u;
    TEST_ASSERT_EQUAL_UINT(1u, feed(&delimiter, 1u, &used));
    TEST_ASSERT_EQUAL_UINT8(0u, out[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, rw_cobs_deframer_bad_frames(&d));
    TEST_ASSERT_EQUAL_UINT32(0u, rw_cobs_deframer_frames(&d));
}

static void test_a_frame_larger_than_the_callers_buffer_is_not_a_frame(void)
{
    uint8_t frame[40];
    for (unsigned i = 0u; i < sizeof frame; ++i) {
        frame[i] = (uint8_t)(i + 1u);
    }
    uint8_t wire[64];
    const size_t n = wire_of(frame, sizeof frame, wire, sizeof wire);
    uint8_t small[16];
    size_t len = 0u;
    for (size_t i = 0u; i < n && len == 0u; ++i) {
        len = rw_cobs_deframer_put(&d, wire[i], small, sizeof small);
    }
    TEST_ASSERT_EQUAL_UINT(1u, len);
    TEST_ASSERT_EQUAL_UINT8(0u, small[0]);
    TEST_ASSERT_EQUAL_UINT32(1u, rw_cobs_deframer_bad_frames(&d));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_one_frame_byte_by_byte_then_nothing_more);
    RUN_TEST(test_two_frames_in_one_stream_and_empty_delimiters_skipped);
    RUN_TEST(test_malformed_cobs_is_handed_on_as_not_a_frame_then_resync);
    RUN_TEST(test_an_over_long_run_is_one_bad_frame_at_its_delimiter);
    RUN_TEST(test_a_frame_larger_than_the_callers_buffer_is_not_a_frame);
    return UNITY_END();
}
