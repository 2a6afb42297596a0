/*
 * Unity tests of rw_lowpass (first-order low-pass). Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_lowpass.h"

static rw_lowpass lp;

void setUp(void)
{
    const rw_lowpass_config cfg = {.tau_s = 0.05f};
    rw_lowpass_init(&lp, &cfg);
}

void tearDown(void) {}

static void test_step_response_reaches_63_percent_after_one_tau(void)
{
    float y = 0.0f;
    for (int k = 0; k < 50; ++k) {
        y = rw_lowpass_step(&lp, 1.0f, 0.001f);
    }
    /* backward Euler: 1 - (50/51)^50 = 0.6285; continuous 1 - 1/e = 0.6321 */
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.6285f, y);
    for (int k = 0; k < 1000; ++k) {
        y = rw_lowpass_step(&lp, 1.0f, 0.001f);
    }
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.0f, y);
}

static void test_step_response_is_monotonic(void)
{
    float prev = 0.0f;
    for (int k = 0; k < 300; ++k) {
        const float y = rw_lowpass_step(&lp, 2.0f, 0.001f);
        TEST_ASSERT_TRUE(y >= prev);
        TEST_ASSERT_TRUE(y <= 2.0f);
        prev = y;
    }
}

static void test_zero_tau_passes_through(void)
{
    lp.cfg.tau_s = 0.0f;
    TEST_ASSERT_EQUAL_FLOAT(3.5f, rw_lowpass_step(&lp, 3.5f, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(-1.25f, rw_lowpass_step(&lp, -1.25f, 0.001f));
}

static void test_bad_input_keeps_output(void)
{
    const float held = rw_lowpass_step(&lp, 1.0f, 0.01f);
    TEST_ASSERT_EQUAL_FLOAT(held, rw_lowpass_step(&lp, NAN, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(held, rw_lowpass_step(&lp, INFINITY, 0.001f));
    TEST_ASSERT_EQUAL_FLOAT(held, rw_lowpass_step(&lp, 1.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(held, rw_lowpass_step(&lp, 1.0f, -0.001f));
    TEST_ASSERT_EQUAL_FLOAT(held, rw_lowpass_step(&lp, 1.0f, NAN));
    TEST_ASSERT_TRUE(isfinite(rw_lowpass_output(&lp)));
}

static void test_reset_to(void)
{
    rw_lowpass_reset_to(&lp, 2.5f);
    TEST_ASSERT_EQUAL_FLOAT(2.5f, rw_lowpass_step(&lp, 2.5f, 0.001f));
    rw_lowpass_reset_to(&lp, NAN);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_lowpass_output(&lp));
    rw_lowpass_step(&lp, 1.0f, 0.01f);
    rw_lowpass_reset(&lp);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_lowpass_output(&lp));
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
    RUN_TEST(test_reset_to);
    RUN_TEST(test_config_validation);
    return UNITY_END();
}
