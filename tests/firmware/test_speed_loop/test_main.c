/*
 * Unity tests of rw_speed_loop (the rope speed loop as one controller): OFF holds the ESC minimum; DRIVE
 * ramps the setpoint at the rise rate and drives the pulse up; a wheel at the setpoint settles the PI; LAND
 * ramps to zero, then the ESC minimum; AIRBORNE lowers the setpoint onto the guard more gently than the
 * fall rate and never drives the throttle under what holds the guard speed; a silent encoder holds the
 * pulse; a prepared loop and one converting per step give the same pulses. The encoder is a wheel at a set
 * rope speed (64 edges/rev, 15 mm, edge times in nanoseconds). Run with `pio test -e native`.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_protocol.h"
#include "rw_speed_loop.h"

#define DT_US 2000u
#define DT_S 0.002f
#define COUNTS_PER_REV 64u
#define RADIUS_M 0.015
#define BATTERY_V 14.8f
#define TWO_PI 6.283185307179586

static rw_speed_loop loop;
static struct {
    uint64_t t_ns;
    uint64_t next_edge_ns;
    uint64_t period_ns; /* 0: stopped */
    uint32_t counts;
    uint32_t last_edge_us;
} wheel;

static void wheel_at(double rope_mps)
{
    wheel.period_ns = rope_mps > 0.0 ? (uint64_t)(TWO_PI * RADIUS_M / (rope_mps * COUNTS_PER_REV) * 1e9) : 0u;
    if (wheel.period_ns != 0u && wheel.next_edge_ns <= wheel.t_ns) {
        wheel.next_edge_ns = wheel.t_ns + wheel.period_ns;
    }
}

/* Advance the wheel by one step, measure, and step the loop; returns the pulse. */
static uint16_t step(rw_speed_loop *l, rw_speed_loop_mode mode, float target_mps)
{
    wheel.t_ns += (uint64_t)DT_US * 1000u;
    while (wheel.period_ns != 0u && wheel.next_edge_ns <= wheel.t_ns) {
        ++wheel.counts;
        wheel.last_edge_us = (uint32_t)(wheel.next_edge_ns / 1000u);
        wheel.next_edge_ns += wheel.period_ns;
    }
    const uint32_t now_us = (uint32_t)(wheel.t_ns / 1000u);
    (void)rw_speed_loop_measure(l, wheel.counts, wheel.last_edge_us, now_us, DT_S);
    return rw_speed_loop_step(l, mode, target_mps, now_us, DT_S);
}

void setUp(void)
{
    memset(&wheel, 0, sizeof wheel);
    rw_speed_loop_init(&loop);
    rw_speed_loop_set_battery(&loop, BATTERY_V);
    rw_speed_loop_prepare(&loop, DT_S);
}

void tearDown(void) {}

static void test_off_holds_the_esc_minimum(void)
{
    for (int i = 0; i < 10; ++i) {
        TEST_ASSERT_EQUAL_UINT16(loop.throttle.cfg.pulse_min_us, step(&loop, RW_SPEED_LOOP_OFF, 5.0f));
    }
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_speed_loop_setpoint_mps(&loop));
}

static void test_drive_ramps_at_the_rise_rate_and_settles_on_a_wheel_at_speed(void)
{
    const float rate = loop.ramp.cfg.rate_up_per_s;
    uint16_t pulse = 0u;
    for (int i = 0; i < 100; ++i) {
        wheel_at((double)rw_speed_loop_setpoint_mps(&loop)); /* the rope follows the setpoint */
        pulse = step(&loop, RW_SPEED_LOOP_DRIVE, 20.0f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, rate * 100.0f * DT_S, rw_speed_loop_setpoint_mps(&loop));
    TEST_ASSERT_TRUE(pulse > loop.throttle.cfg.pulse_min_us);
    TEST_ASSERT_TRUE(pulse <= RW_ESC_PULSE_MAX_US);
}

static void test_land_ramps_to_zero_then_the_esc_minimum(void)
{
    for (int i = 0; i < 500; ++i) {
        wheel_at((double)rw_speed_loop_setpoint_mps(&loop));
        step(&loop, RW_SPEED_LOOP_DRIVE, 4.0f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 4.0f, rw_speed_loop_setpoint_mps(&loop));
    uint16_t pulse = 0u;
    int steps = 0;
    while (rw_speed_loop_setpoint_mps(&loop) > 0.0f && steps < 5000) {
        wheel_at((double)rw_speed_loop_setpoint_mps(&loop));
        pulse = step(&loop, RW_SPEED_LOOP_LAND, 4.0f); /* the target is ignored while landing */
        ++steps;
    }
    TEST_ASSERT_FLOAT_WITHIN(0.02f, 4.0f / loop.ramp.cfg.rate_down_per_s, (float)steps * DT_S);
    TEST_ASSERT_EQUAL_UINT16(loop.throttle.cfg.pulse_min_us, pulse);
}

static void test_airborne_approaches_the_guard_gently_with_a_throttle_floor(void)
{
    for (int i = 0; i < 1000; ++i) {
        wheel_at((double)rw_speed_loop_setpoint_mps(&loop));
        step(&loop, RW_SPEED_LOOP_DRIVE, 6.0f);
    }
    const float guard = loop.cfg.guard_mps;
    const float fall = loop.ramp.cfg.rate_down_per_s;
    float before = rw_speed_loop_setpoint_mps(&loop);
    wheel_at(0.5); /* the rope far too slow: the PI would cut the throttle */
    for (int i = 0; i < 50; ++i) {
        step(&loop, RW_SPEED_LOOP_AIRBORNE, guard);
        const float now = rw_speed_loop_setpoint_mps(&loop);
        TEST_ASSERT_TRUE(now >= guard);
        TEST_ASSERT_TRUE(before - now <= fall * DT_S + 1e-4f); /* never faster than the fall rate */
        before = now;
    }
    /* the throttle never under what holds the guard speed without load */
    const int32_t floor_q16 = rw_throttle_map_feed_forward(&loop.throttle, loop.state.guard_q16, BATTERY_V);
    TEST_ASSERT_TRUE(rw_pi_controller_output_q16(&loop.pi) >= floor_q16);
    TEST_ASSERT_TRUE(rw_speed_loop_pulse_us(&loop) >= rw_throttle_map_pulse_us(&loop.throttle, floor_q16));
}

static void test_a_silent_encoder_holds_the_pulse(void)
{
    for (int i = 0; i < 1000; ++i) {
        wheel_at((double)rw_speed_loop_setpoint_mps(&loop));
        step(&loop, RW_SPEED_LOOP_DRIVE, 5.0f);
    }
    wheel_at(0.0); /* edges stop: a stale reading, not a stopped rope (the supervisor decides on faults) */
    uint16_t held = 0u;
    for (int i = 0; i < 5; ++i) { /* the first steps still see the last edges */
        held = step(&loop, RW_SPEED_LOOP_DRIVE, 5.0f);
    }
    for (int i = 0; i < 50; ++i) {
        TEST_ASSERT_EQUAL_UINT16(held, step(&loop, RW_SPEED_LOOP_DRIVE, 5.0f));
    }
}

static void test_prepared_and_per_step_conversion_agree(void)
{
    static rw_speed_loop other;
    rw_speed_loop_init(&other);
    rw_speed_loop_set_battery(&other, BATTERY_V);
    rw_speed_loop_prepare(&other, 0.0f); /* prepared for no step: every step converts for itself */
    for (int i = 0; i < 400; ++i) {
        wheel_at(i < 200 ? 0.02 * i : 3.0);
        const uint64_t t = wheel.t_ns;
        const uint32_t counts = wheel.counts;
        const uint32_t edge = wheel.last_edge_us;
        const uint64_t next = wheel.next_edge_ns;
        const uint16_t a = step(&loop, RW_SPEED_LOOP_DRIVE, 4.0f);
        wheel.t_ns = t; /* replay the same wheel for the other loop */
        wheel.counts = counts;
        wheel.last_edge_us = edge;
        wheel.next_edge_ns = next;
        const uint16_t b = step(&other, RW_SPEED_LOOP_DRIVE, 4.0f);
        TEST_ASSERT_EQUAL_UINT16(a, b);
    }
}

/* The prepare of each part, in any order, is the whole prepare: a PARAM_SET converts only its part. */
static void test_prepare_by_part_is_the_whole_prepare(void)
{
    static rw_speed_loop whole;
    static rw_speed_loop parts;
    rw_speed_loop_init(&whole);
    rw_speed_loop_set_battery(&whole, 14.8f);
    whole.pi.cfg.kp = 0.07f;
    whole.ramp.cfg.rate_up_per_s = 33.0f;
    whole.estimator.cfg.filter_tau_s = 0.02f;
    whole.throttle.cfg.kv_rpm_per_v = 900.0f;
    whole.cfg.guard_mps = 3.5f;
    parts = whole;
    rw_speed_loop_prepare(&whole, 0.002f);
    rw_speed_loop_prepare_guard(&parts);
    rw_speed_loop_prepare_throttle(&parts);
    rw_speed_loop_prepare_pi(&parts, 0.002f);
    rw_speed_loop_prepare_ramp(&parts, 0.002f);
    rw_speed_loop_prepare_estimator(&parts, 0.002f);
    TEST_ASSERT_EQUAL_MEMORY(&whole, &parts, sizeof whole);
    /* one part alone changes that part only */
    parts.pi.cfg.kp = 0.01f;
    const rw_speed_loop before = parts;
    rw_speed_loop_prepare_pi(&parts, 0.002f);
    TEST_ASSERT_EQUAL_MEMORY(&before.estimator, &parts.estimator, sizeof parts.estimator);
    TEST_ASSERT_EQUAL_MEMORY(&before.ramp, &parts.ramp, sizeof parts.ramp);
    TEST_ASSERT_EQUAL_MEMORY(&before.throttle, &parts.throttle, sizeof parts.throttle);
    TEST_ASSERT_TRUE(before.pi.state.kp_q24 != parts.pi.state.kp_q24);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_off_holds_the_esc_minimum);
    RUN_TEST(test_drive_ramps_at_the_rise_rate_and_settles_on_a_wheel_at_speed);
    RUN_TEST(test_land_ramps_to_zero_then_the_esc_minimum);
    RUN_TEST(test_airborne_approaches_the_guard_gently_with_a_throttle_floor);
    RUN_TEST(test_a_silent_encoder_holds_the_pulse);
    RUN_TEST(test_prepared_and_per_step_conversion_agree);
    RUN_TEST(test_prepare_by_part_is_the_whole_prepare);
    return UNITY_END();
}
