/*
 * Unity tests of rw_ramp (setpoint rate limiter). Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_float_bits.h"
#include "rw_ramp.h"

static rw_ramp ramp;

void setUp(void)
{
    const rw_ramp_config cfg = {.rate_up_per_s = 10.0f, .rate_down_per_s = 2.0f};
    rw_ramp_init(&ramp, &cfg);
}

void tearDown(void) {}

/* The step runs in Q16.16 (1/65536 unit): the tests speak floats. */
static float step(float target, float dt_s)
{
    return rw_f32_from_q16(rw_ramp_step(&ramp, rw_f32_to_q16(target), dt_s));
}

static void test_rise_at_exact_rate_and_land_on_target(void)
{
    float prev = 0.0f;
    int moving_steps = 0;
    for (int k = 0; k < 600; ++k) {
        const float y = step(5.0f, 0.001f);
        const float d = y - prev;
        if (d > 0.0f) {
            ++moving_steps;
            TEST_ASSERT_TRUE(d <= 0.01f + 1.0f / 65536.0f);
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
        y = step(0.0f, 0.01f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, 2.0f, y); /* 1 s at 2 units/s, to the Q16 LSB */
    for (int k = 0; k < 150; ++k) {
        y = step(0.0f, 0.01f);
    }
    TEST_ASSERT_EQUAL_FLOAT(0.0f, y);
}

static void test_zero_rate_is_unlimited(void)
{
    ramp.cfg.rate_up_per_s = 0.0f;
    TEST_ASSERT_EQUAL_FLOAT(7.0f, step(7.0f, 0.001f));
}

static void test_bad_input_keeps_output(void)
{
    rw_ramp_reset_to(&ramp, 2.0f);
    TEST_ASSERT_EQUAL_FLOAT(2.0f, step(5.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, step(5.0f, -1.0f));
    TEST_ASSERT_EQUAL_FLOAT(2.0f, step(5.0f, NAN));
    /* the extremes of the Q16 range: no overflow, the step still bounded by the rate */
    TEST_ASSERT_EQUAL_INT32(rw_f32_to_q16(2.0f) + 655, rw_ramp_step(&ramp, INT32_MAX, 0.001f));
    rw_ramp_reset_to(&ramp, -2.0f);
    TEST_ASSERT_EQUAL_INT32(rw_f32_to_q16(-2.0f) - 131, rw_ramp_step(&ramp, INT32_MIN, 0.001f));
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
