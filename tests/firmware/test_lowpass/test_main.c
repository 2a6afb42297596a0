/*
 * Unity tests of rw_lowpass (first-order low-pass). Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_float_bits.h"
#include "rw_lowpass.h"

static rw_lowpass lp;

void setUp(void)
{
    const rw_lowpass_config cfg = {.tau_s = 0.05f};
    rw_lowpass_init(&lp, &cfg);
}

void tearDown(void) {}

/* The filter runs in Q16.16 in and out (state 2^-32): the tests speak floats. */
static float step(float x, float dt_s)
{
    return rw_f32_from_q16(rw_lowpass_step(&lp, rw_f32_to_q16(x), dt_s));
}

static float output(void)
{
    return rw_f32_from_q16(rw_lowpass_output_q16(&lp));
}

static void test_step_response_reaches_63_percent_after_one_tau(void)
{
    float y = 0.0f;
    for (int k = 0; k < 50; ++k) {
        y = step(1.0f, 0.001f);
    }
    /* backward Euler: 1 - (50/51)^50 = 0.6285; continuous 1 - 1/e = 0.6321 */
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.6285f, y);
    for (int k = 0; k < 1000; ++k) {
        y = step(1.0f, 0.001f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1.0f / 65536.0f, 1.0f, y);
}

static void test_step_response_is_monotonic(void)
{
    float prev = 0.0f;
    for (int k = 0; k < 300; ++k) {
        const float y = step(2.0f, 0.001f);
        TEST_ASSERT_TRUE(y >= prev);
        TEST_ASSERT_TRUE(y <= 2.0f);
        prev = y;
    }
}

static void test_zero_tau_passes_through(void)
{
    lp.cfg.tau_s = 0.0f;
    TEST_ASSERT_EQUAL_FLOAT(3.5f, step(3.5f, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(-1.25f, step(-1.25f, 0.001f));
}

static void test_bad_input_keeps_output(void)
{
    const float held = step(1.0f, 0.01f);
    TEST_ASSERT_EQUAL_FLOAT(held, step(1.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(held, step(1.0f, -0.001f));
    TEST_ASSERT_EQUAL_FLOAT(held, step(1.0f, NAN));
    /* the ends of the Q16 range: no overflow, the output moves towards them and stays in range */
    const int32_t up = rw_lowpass_step(&lp, INT32_MAX, 0.001f);
    TEST_ASSERT_TRUE(up > rw_f32_to_q16(held));
    const int32_t down = rw_lowpass_step(&lp, INT32_MIN, 1.0f);
    TEST_ASSERT_TRUE(down < up);
}

/* The state is kept to 2^-32: a 1 LSB input with tau 1 s at 1 ms steps (alpha 0.1 %) is reached, not stuck
 * under the rounding of a Q16 state. */
static void test_small_inputs_are_not_lost_to_the_resolution(void)
{
    lp.cfg.tau_s = 1.0f;
    int32_t y = 0;
    for (int k = 0; k < 10000; ++k) {
        y = rw_lowpass_step(&lp, 1, 0.001f);
    }
    TEST_ASSERT_EQUAL_INT32(1, y);
}

static void test_reset_to(void)
{
    rw_lowpass_reset_to(&lp, rw_f32_to_q16(2.5f));
    TEST_ASSERT_EQUAL_FLOAT(2.5f, step(2.5f, 0.001f));
    (void)step(1.0f, 0.01f);
    rw_lowpass_reset(&lp);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, output());
}

/* prepare computes the coefficient ahead (the steps then divide nothing); the outputs are the same. */
static void test_prepare_changes_no_output(void)
{
    rw_lowpass other;
    const rw_lowpass_config cfg = {.tau_s = 0.05f};
    rw_lowpass_init(&other, &cfg);
    rw_lowpass_prepare(&other, 0.01f);
    rw_lowpass_prepare(&other, -1.0f); /* ignored */
    for (int k = 0; k < 50; ++k) {
        const int32_t x = rw_f32_to_q16(k < 25 ? 3.0f : -1.0f);
        TEST_ASSERT_EQUAL_INT32(rw_lowpass_step(&lp, x, 0.01f), rw_lowpass_step(&other, x, 0.01f));
    }
}

static void test_config_validation(void)
{
    rw_lowpass_config cfg = {.tau_s = 0.0f};
    TEST_ASSERT_TRUE(rw_lowpass_config_is_valid(&cfg));
    cfg.tau_s = -0.01f;
    TEST_ASSERT_FALSE(rw_lowpass_config_is_valid(&cfg));
    cfg.tau_s = NAN;
    TEST_ASSERT_FALSE(rw_lowpass_config_is_valid(&cfg));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_step_response_reaches_63_percent_after_one_tau);
    RUN_TEST(test_step_response_is_monotonic);
    RUN_TEST(test_zero_tau_passes_through);
    RUN_TEST(test_bad_input_keeps_output);
    RUN_TEST(test_small_inputs_are_not_lost_to_the_resolution);
    RUN_TEST(test_reset_to);
    RUN_TEST(test_prepare_changes_no_output);
    RUN_TEST(test_config_validation);
    return UNITY_END();
}
