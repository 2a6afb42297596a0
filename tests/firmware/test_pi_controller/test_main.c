/*
 * Unity tests of rw_pi_controller (PI with feed-forward, limits, anti-windup).
 * The closed-loop tests use a first-order rope drive plant: 32 m/s at full throttle, tau 80 ms,
 * stepped at the 1 ms firmware tick. Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_float_bits.h"
#include "rw_pi_controller.h"

#define DT_S 0.001f
#define FULL_MPS 32.0f
/* exp(-DT_S / 0.08 s) */
#define PLANT_A 0.98757780f

static rw_pi_controller pi;

void setUp(void)
{
    const rw_pi_controller_config cfg = {.kp = 0.03f, .ki_per_s = 0.4f, .out_min = 0.0f, .out_max = 1.0f};
    rw_pi_controller_init(&pi, &cfg);
}

void tearDown(void) {}

/* The step in Q16.16 (the tests speak floats: converted here; resolution 1/65536) */
static float step(float setpoint, float measurement, float feed_forward, float dt_s)
{
    return rw_f32_from_q16(rw_pi_controller_step(&pi, rw_f32_to_q16(setpoint), rw_f32_to_q16(measurement),
                                                 rw_f32_to_q16(feed_forward), dt_s));
}

static float integral(void)
{
    return (float)pi.state.integral_q32 * (1.0f / 4294967296.0f);
}

static float plant_step(float v_mps, float throttle, float gain)
{
    return PLANT_A * v_mps + (1.0f - PLANT_A) * gain * FULL_MPS * throttle;
}

static void test_proportional_plus_feed_forward(void)
{
    pi.cfg.kp = 0.5f;
    pi.cfg.ki_per_s = 0.0f;
    rw_pi_controller_prepare(&pi, DT_S); /* a changed config is prepared */
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, 0.25f + 0.5f * 1.0f, step(3.0f, 2.0f, 0.25f, DT_S));
}

static void test_integral_ramps_at_ki_times_error(void)
{
    pi.cfg.kp = 0.0f;
    pi.cfg.ki_per_s = 2.0f;
    rw_pi_controller_prepare(&pi, DT_S);
    float u = 0.0f;
    for (int k = 0; k < 100; ++k) {
        u = step(1.5f, 1.0f, 0.0f, DT_S);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.1f, u); /* 2 * 0.5 * 0.1 s */
    /* the accessor the load-loss check reads: the integral term to 2^-16 */
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, integral(), rw_pi_controller_integral(&pi));
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, 0.1f, rw_pi_controller_integral(&pi));
}

static void test_closed_loop_removes_feed_forward_error(void)
{
    float v = 0.0f;
    float peak = 0.0f;
    for (int k = 0; k < 3000; ++k) {
        const float u = step(10.0f, v, 10.0f / FULL_MPS, DT_S);
        v = plant_step(v, u, 0.75f); /* feed-forward 25 % optimistic */
        peak = v > peak ? v : peak;
    }
    TEST_ASSERT_FLOAT_WITHIN(0.02f, 10.0f, v);
    TEST_ASSERT_TRUE(peak < 11.0f);
}

static void test_no_windup_while_saturated_and_prompt_exit(void)
{
    float v = 0.0f;
    const float ff = 20.0f / FULL_MPS;
    float integral_at_1s = 0.0f;
    for (int k = 0; k < 3000; ++k) {
        const float u = step(20.0f, v, ff, DT_S);
        v = plant_step(v, u, 0.5f); /* only 16 m/s reachable */
        if (k == 1999) {
            integral_at_1s = integral();
        }
    }
    TEST_ASSERT_EQUAL_INT(1, pi.state.saturation);
    TEST_ASSERT_EQUAL_FLOAT(1.0f, rw_f32_from_q16(rw_pi_controller_output_q16(&pi)));
    /* clamped for the last second: the integral did not move, and it holds the output just at 1 */
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, integral_at_1s, integral());
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 1.0f - ff - 0.03f * (20.0f - v), integral());
    /* error reverses: out of saturation on the first step */
    TEST_ASSERT_TRUE(step(5.0f, v, 5.0f / FULL_MPS, DT_S) < 1.0f);
}

static void test_lower_limit_symmetric(void)
{
    pi.cfg.kp = 0.01f;
    pi.cfg.ki_per_s = 1.0f;
    pi.cfg.out_min = -1.0f;
    rw_pi_controller_prepare(&pi, DT_S);
    float u = 0.0f;
    for (int k = 0; k < 3000; ++k) {
        u = step(0.0f, 5.0f, 0.0f, DT_S);
    }
    TEST_ASSERT_EQUAL_FLOAT(-1.0f, u);
    TEST_ASSERT_EQUAL_INT(-1, pi.state.saturation);
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, -0.95f, integral()); /* kp 0.01 x 5 to Q16 */
    TEST_ASSERT_TRUE(step(5.0f, 0.0f, 0.0f, DT_S) > -1.0f);
}

static void test_bad_input_holds_output(void)
{
    const float held = step(10.0f, 5.0f, 0.1f, DT_S);
    TEST_ASSERT_EQUAL_FLOAT(held, step(10.0f, 5.0f, 0.1f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(held, step(10.0f, 5.0f, 0.1f, -DT_S));
    TEST_ASSERT_EQUAL_FLOAT(held, step(10.0f, 5.0f, 0.1f, NAN));
    pi.cfg.out_min = 2.0f; /* invalid: out_min > out_max */
    rw_pi_controller_prepare(&pi, DT_S);
    TEST_ASSERT_EQUAL_FLOAT(held, step(10.0f, 5.0f, 0.1f, DT_S));
    pi.cfg.out_min = 0.0f;
    pi.cfg.kp = NAN; /* invalid gain */
    rw_pi_controller_prepare(&pi, DT_S);
    TEST_ASSERT_EQUAL_FLOAT(held, step(10.0f, 5.0f, 0.1f, DT_S));
}

static void test_output_within_limits_for_extreme_input(void)
{
    const float inputs[] = {-1e30f, -1.0f, 0.0f, 1.0f, 1e30f, 3.0e38f}; /* saturate at +-32768 in Q16 */
    for (unsigned i = 0; i < sizeof inputs / sizeof inputs[0]; ++i) {
        for (unsigned j = 0; j < sizeof inputs / sizeof inputs[0]; ++j) {
            const float u = step(inputs[i], inputs[j], inputs[(i + j) % 6u], DT_S);
            TEST_ASSERT_TRUE(isfinite(u));
            TEST_ASSERT_TRUE(u >= 0.0f && u <= 1.0f);
        }
    }
}

static void test_defaults_valid(void)
{
    rw_pi_controller_config cfg;
    rw_pi_controller_config_defaults(&cfg);
    TEST_ASSERT_TRUE(rw_pi_controller_config_is_valid(&cfg));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, cfg.out_min);
    TEST_ASSERT_EQUAL_FLOAT(1.0f, cfg.out_max);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_proportional_plus_feed_forward);
    RUN_TEST(test_integral_ramps_at_ki_times_error);
    RUN_TEST(test_closed_loop_removes_feed_forward_error);
    RUN_TEST(test_no_windup_while_saturated_and_prompt_exit);
    RUN_TEST(test_lower_limit_symmetric);
    RUN_TEST(test_bad_input_holds_output);
    RUN_TEST(test_output_within_limits_for_extreme_input);
    RUN_TEST(test_defaults_valid);
    return UNITY_END();
}
