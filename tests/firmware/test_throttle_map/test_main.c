/*
 * Unity tests of rw_throttle_map (feed-forward throttle, throttle <-> ESC pulse).
 * Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_float_bits.h"
#include "rw_throttle_map.h"

/* 1400 rpm/V x 14.8 V = 20,720 rpm; at a 15 mm wheel that is 32.55 m/s of rope. */
#define FULL_MPS 32.5501f

static rw_throttle_map map;

void setUp(void)
{
    const rw_throttle_map_config cfg = {
        .kv_rpm_per_v = 1400.0f, .wheel_radius_m = 0.015f, .pulse_min_us = 1050u, .pulse_max_us = 2000u};
    rw_throttle_map_init(&map, &cfg);
}

void tearDown(void) {}

/* The feed-forward and the pulse run in Q16.16 (1/65536 of full throttle): the tests speak floats. */
static float ff(float rope_mps, float battery_v)
{
    return rw_f32_from_q16(rw_throttle_map_feed_forward(&map, rw_f32_to_q16(rope_mps), battery_v));
}

static uint16_t pulse_of(float throttle)
{
    return rw_throttle_map_pulse_us(&map, rw_f32_to_q16(throttle));
}

static void test_feed_forward_from_kv_battery_radius(void)
{
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 2.6f / FULL_MPS, ff(2.6f, 14.8f));
    /* 15,000 rpm = 23.56 m/s */
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 15000.0f / 20720.0f, ff(23.56f, 14.8f));
    TEST_ASSERT_EQUAL_FLOAT(1.0f, ff(50.0f, 14.8f));
}

static void test_feed_forward_zero_for_bad_input(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, ff(-1.0f, 14.8f));
    TEST_ASSERT_EQUAL_INT32(0, rw_throttle_map_feed_forward(&map, INT32_MIN, 14.8f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, ff(5.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, ff(5.0f, NAN));
}

static void test_pulse_end_points_and_midpoint(void)
{
    TEST_ASSERT_EQUAL_UINT16(1050u, pulse_of(0.0f));
    TEST_ASSERT_EQUAL_UINT16(1525u, pulse_of(0.5f));
    TEST_ASSERT_EQUAL_UINT16(2000u, pulse_of(1.0f));
    TEST_ASSERT_EQUAL_UINT16(2000u, pulse_of(7.0f));
}

static void test_pulse_never_below_esc_minimum(void)
{
    TEST_ASSERT_EQUAL_UINT16(1050u, pulse_of(-0.5f));
    TEST_ASSERT_EQUAL_UINT16(1050u, rw_throttle_map_pulse_us(&map, INT32_MIN));
    TEST_ASSERT_EQUAL_UINT16(2000u, rw_throttle_map_pulse_us(&map, INT32_MAX));
    for (int i = -100; i <= 200; ++i) {
        const uint16_t pulse = pulse_of((float)i * 0.01f);
        TEST_ASSERT_TRUE(pulse >= 1050u && pulse <= 2000u);
    }
}

static void test_out_of_range_config_narrowed(void)
{
    map.cfg.pulse_min_us = 900u;
    map.cfg.pulse_max_us = 2500u;
    rw_throttle_map_prepare(&map); /* a changed config is prepared */
    TEST_ASSERT_FALSE(rw_throttle_map_config_is_valid(&map.cfg));
    TEST_ASSERT_EQUAL_UINT16(1000u, pulse_of(0.0f));
    TEST_ASSERT_EQUAL_UINT16(2000u, pulse_of(1.0f));
}

static void test_pulse_round_trip(void)
{
    for (uint16_t pulse = 1050u; pulse <= 2000u; pulse = (uint16_t)(pulse + 5u)) {
        TEST_ASSERT_EQUAL_UINT16(pulse,
                                 pulse_of(rw_throttle_map_throttle_from_pulse(&map, pulse)));
    }
}

static void test_defaults_valid(void)
{
    rw_throttle_map_config cfg;
    rw_throttle_map_config_defaults(&cfg);
    TEST_ASSERT_TRUE(rw_throttle_map_config_is_valid(&cfg));
    TEST_ASSERT_EQUAL_UINT16(1000u, cfg.pulse_min_us);
    TEST_ASSERT_EQUAL_UINT16(2000u, cfg.pulse_max_us);
}

/* The factor prepared for a battery voltage gives the feed-forward of the law to the Q16 LSB; a
 * new voltage or a new kv is followed at once. */
static void test_prepared_battery_factor_follows_voltage_and_kv(void)
{
    rw_throttle_map_prepare_battery(&map, 14.8f);
    const float at_14v8 = ff(5.0f, 14.8f);
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, (60.0f * 5.0f) / (6.28318530718f * 0.015f * 1400.0f * 14.8f), at_14v8);
    TEST_ASSERT_FLOAT_WITHIN(2.0f / 65536.0f, at_14v8 * 14.8f / 12.0f, ff(5.0f, 12.0f));
    map.cfg.kv_rpm_per_v = 700.0f;
    rw_throttle_map_prepare(&map);
    TEST_ASSERT_FLOAT_WITHIN(2.0f / 65536.0f, 2.0f * at_14v8, ff(5.0f, 14.8f));
    map.cfg.kv_rpm_per_v = 0.0f; /* invalid: no feed-forward */
    rw_throttle_map_prepare(&map);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, ff(5.0f, 14.8f));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_feed_forward_from_kv_battery_radius);
    RUN_TEST(test_feed_forward_zero_for_bad_input);
    RUN_TEST(test_pulse_end_points_and_midpoint);
    RUN_TEST(test_pulse_never_below_esc_minimum);
    RUN_TEST(test_out_of_range_config_narrowed);
    RUN_TEST(test_pulse_round_trip);
    RUN_TEST(test_defaults_valid);
    RUN_TEST(test_prepared_battery_factor_follows_voltage_and_kv);
    return UNITY_END();
}
