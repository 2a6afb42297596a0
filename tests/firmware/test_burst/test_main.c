/*
 * Unity tests of rw_burst: a capture takes exactly the asked number of samples, in order, with the times of its
 * first samples; the stream hands them out in frames of RW_BURST_SAMPLES_PER_FRAME with their indices (the last
 * frame short, its unused samples zero) and ends idle; a second burst is refused while one is captured or
 * streamed (BURST_BUSY, with what is left), a size of 0 or over RW_BURST_MAX_SAMPLES is refused (OUT_OF_RANGE,
 * the maximum). Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_burst.h"

static rw_burst burst;

void setUp(void)
{
    rw_burst_reset(&burst);
}

void tearDown(void) {}

static rw_burst_sample sample_n(unsigned n)
{
    rw_burst_sample s = { .encoder_counts = (uint16_t)(3u * n), .encoder_edge_us = (uint16_t)(1000u * n + 7u),
                          .esc_pulse_third_us = (uint16_t)(3000u + n), .battery_mv = (uint16_t)(12000u - n) };
    return s;
}

static void capture(unsigned count, uint32_t t0_us)
{
    int32_t detail = -1;
    TEST_ASSERT_EQUAL_UINT8(0u, rw_burst_start(&burst, (uint16_t)count, &detail));
    for (unsigned i = 0u; i < count; ++i) {
        TEST_ASSERT_TRUE(rw_burst_capturing(&burst));
        const rw_burst_sample s = sample_n(i);
        rw_burst_record(&burst, 500u + i, t0_us + 1000u * i, 1000u, &s);
    }
}

static void test_capture_then_stream_every_sample_in_order(void)
{
    capture(14u, 0xFFFFFC00u); /* the uptime clock wraps during the burst */
    TEST_ASSERT_FALSE(rw_burst_capturing(&burst));
    TEST_ASSERT_TRUE(rw_burst_streaming(&burst));
    unsigned seen = 0u;
    while (rw_burst_streaming(&burst)) {
        rw_msg_burst_data msg;
        rw_burst_next_frame(&burst, &msg);
        TEST_ASSERT_EQUAL_UINT16(0u, msg.burst_id);
        TEST_ASSERT_EQUAL_UINT32(500u, msg.start_time_ms);
        TEST_ASSERT_EQUAL_UINT32(0xFFFFFC00u, msg.start_time_us);
        TEST_ASSERT_EQUAL_UINT16(1000u, msg.tick_us);
        TEST_ASSERT_EQUAL_UINT16(14u, msg.sample_count);
        TEST_ASSERT_EQUAL_UINT16(seen, msg.first_sample);
        for (unsigned k = 0u; k < RW_BURST_SAMPLES_PER_FRAME; ++k) {
            rw_burst_sample got;
            rw_burst_sample_get(msg.samples, k, &got);
            if (seen + k < 14u) {
                const rw_burst_sample want = sample_n(seen + k);
                TEST_ASSERT_EQUAL_MEMORY(&want, &got, sizeof want);
            } else {
                TEST_ASSERT_EQUAL_UINT16(0u, got.encoder_counts);
                TEST_ASSERT_EQUAL_UINT16(0u, got.esc_pulse_third_us);
            }
        }
        seen += RW_BURST_SAMPLES_PER_FRAME;
    }
    TEST_ASSERT_EQUAL_UINT(18u, seen); /* 6 + 6 + 2: three frames */
    TEST_ASSERT_EQUAL_UINT8(RW_BURST_IDLE, burst.state.phase);
}

static void test_a_second_burst_is_refused_until_the_first_is_streamed(void)
{
    int32_t detail = 0;
    TEST_ASSERT_EQUAL_UINT8(0u, rw_burst_start(&burst, 10u, &detail));
    const rw_burst_sample s = sample_n(0u);
    for (unsigned i = 0u; i < 4u; ++i) {
        rw_burst_record(&burst, i, 1000u * i, 1000u, &s);
    }
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BURST_BUSY, rw_burst_start(&burst, 5u, &detail));
    TEST_ASSERT_EQUAL_INT32(10, detail); /* 6 to capture + 4 to stream */
    for (unsigned i = 4u; i < 10u; ++i) {
        rw_burst_record(&burst, i, 1000u * i, 1000u, &s);
    }
    rw_msg_burst_data msg;
    rw_burst_next_frame(&burst, &msg);
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BURST_BUSY, rw_burst_start(&burst, 5u, &detail));
    TEST_ASSERT_EQUAL_INT32(4, detail); /* 4 still to stream */
    rw_burst_next_frame(&burst, &msg);
    TEST_ASSERT_EQUAL_UINT8(0u, rw_burst_start(&burst, 5u, &detail));
    TEST_ASSERT_EQUAL_UINT16(1u, burst.state.burst_id);
}

static void test_sizes_out_of_range_are_refused_with_the_maximum(void)
{
    int32_t detail = 0;
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, rw_burst_start(&burst, 0u, &detail));
    TEST_ASSERT_EQUAL_INT32((int32_t)RW_BURST_MAX_SAMPLES, detail);
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE,
                            rw_burst_start(&burst, (uint16_t)(RW_BURST_MAX_SAMPLES + 1u), &detail));
    TEST_ASSERT_FALSE(rw_burst_capturing(&burst));
    TEST_ASSERT_EQUAL_UINT8(0u, rw_burst_start(&burst, (uint16_t)RW_BURST_MAX_SAMPLES, &detail));
}

static void test_a_full_buffer_is_captured_whole(void)
{
    capture(RW_BURST_MAX_SAMPLES, 0u);
    TEST_ASSERT_TRUE(rw_burst_streaming(&burst));
    const rw_burst_sample last = sample_n(RW_BURST_MAX_SAMPLES - 1u);
    TEST_ASSERT_EQUAL_MEMORY(&last, &burst.state.samples[RW_BURST_MAX_SAMPLES - 1u], sizeof last);
    unsigned frames = 0u;
    while (rw_burst_streaming(&burst)) {
        rw_msg_burst_data msg;
        rw_burst_next_frame(&burst, &msg);
        ++frames;
    }
    TEST_ASSERT_EQUAL_UINT((RW_BURST_MAX_SAMPLES + RW_BURST_SAMPLES_PER_FRAME - 1u) / RW_BURST_SAMPLES_PER_FRAME, frames);
}

static void test_record_outside_a_capture_changes_nothing(void)
{
    const rw_burst_sample s = sample_n(1u);
    rw_burst_record(&burst, 1u, 1u, 1000u, &s);
    TEST_ASSERT_EQUAL_UINT16(0u, burst.state.captured);
    TEST_ASSERT_EQUAL_UINT8(RW_BURST_IDLE, burst.state.phase);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_capture_then_stream_every_sample_in_order);
    RUN_TEST(test_a_second_burst_is_refused_until_the_first_is_streamed);
    RUN_TEST(test_sizes_out_of_range_are_refused_with_the_maximum);
    RUN_TEST(test_a_full_buffer_is_captured_whole);
    RUN_TEST(test_record_outside_a_capture_changes_nothing);
    return UNITY_END();
}
