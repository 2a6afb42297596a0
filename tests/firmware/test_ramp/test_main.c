/*
 * Unity tests of rw_ramp (setpoint rate limiter). Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_ramp.h"

static rw_ramp ramp;

void setUp(void)
{
    const rw_ramp_config cfg = {.rate_up_per_s = 10.0f, .rate_down_per_s = 2.0f};
    rw_ramp_init(&ramp, &cfg);
}

void tearDown(void) {}

static void test_rise_at_exact_rate_and_land_on_target(void)
{
    float prev = 0.0f;
    int moving_steps = 0;
    for (int k = 0; k < 600; ++k) {
        const float y = rw_ramp_step(&ramp, 5.0f, 0.001f);
        const float d = y - prev;
        if (d > 0.0f) {
            ++moving_steps;
            TEST_ASSERT_TRUE(d <= 0.01f * 1.0001f);
        }
        TEST_ASSERT_TRUE(y <= 5.0f);
        prev = y;
    }
    /* 5 units at 10 units/s with 1 ms steps: 500 steps (one more for the rounding remainder). */
    TEST_ASSERT_INT_WITHIN(1, 500, moving_steps);
    TEST_ASSERT_EQUAL_FLOAT(5.0f, rw_ramp_output(&ramp));
    TEST_ASSERT_TRUE(rw_ramp_at_target(&ramp, 5.0f));
}

static void test_fall_at_the_down_rate(void)
{
    rw_ramp_reset_to(&ramp, 4.0f);
    float y = 0.0f;
    for (int k = 0; k < 100; ++k) {
        y = rw_ramp_step(&ramp, 0.0f, 0.01f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 2.0f, y); /* 1 s at 2 units/s */
    for (int k = 0; k < 150; ++k) {
        y = rw_ramp_step(&ramp, 0.0f, 0.01f);
    }
    TEST_ASSERT_EQUAL_FLOAT(0.0f, y);
}

static void test_zero_rate_is_unlimited(void)
{
    ramp.cfg.rate_up_per_s = 0.0f;
    TEST_ASSERT_EQUAL_FLOAT(7.0f, rw_ramp_step(&ramp, 7.0f, 0.001f));
}

static void test_bad_input_keeps_output(void)
{
    rw_ramp_reset_to(&ramp, 2.0f);
    TEST_ASSERT_EQUAL_FLOAT(2.0f, rw_ramp_step(&ramp, NAN, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, rw_ramp_step(&ramp, INFINITY, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, rw_ramp_step(&ramp, 5.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, rw_ramp_step(&ramp, 5.0f, -1.0f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, rw_ramp_step(&ramp, 5.0f, NAN));
}

static void test_defaults_valid(void)
{
    rw_ramp_config cfg;
    rw_ramp_config_defaults(&cfg);
    TEST_ASSERT_TRUE(rw_ramp_config_is_valid(&cfg));
    TEST_ASSERT_TRUE(cfg.rate_up_per_s > 0.0f);
    TEST_ASSERT_TRUE(cfg.rate_down_per_s > 0.0f);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_rise_at_exact_rate_and_land_on_target);
    RUN_TEST(test_fall_at_the_down_rate);
    RUN_TEST(test_zero_rate_is_unlimited);
    RUN_TEST(test_bad_input_keeps_output);
    RUN_TEST(test_defaults_valid);
    return UNITY_END();
}
