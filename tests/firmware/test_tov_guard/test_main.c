/*
 * Unity tests of rw_tov_guard (airborne setpoint check, loop-collapse detector).
 * Run with `pio test -e native`.
 */
#include <math.h>
#include <unity.h>

#include "rw_tov_guard.h"

#define DT_S 0.001f

static rw_tov_guard guard;

void setUp(void)
{
    const rw_tov_guard_config cfg = {.tov_mps = 2.6f, .margin = 1.2f, .collapse_time_s = 0.25f};
    rw_tov_guard_init(&guard, &cfg);
}

void tearDown(void) {}

/* Steps n times at speed_mps; returns how many steps reported, and the 1-based step of the first. */
static int run_steps(int n, float speed_mps, int *first_step)
{
    int reports = 0;
    *first_step = 0;
    for (int k = 1; k <= n; ++k) {
        if (rw_tov_guard_step(&guard, speed_mps, DT_S)) {
            if (reports == 0) {
                *first_step = k;
            }
            ++reports;
        }
    }
    return reports;
}

static void test_setpoint_floor_is_tov_times_margin(void)
{
    const float floor_mps = rw_tov_guard_min_airborne_mps(&guard);
    TEST_ASSERT_FLOAT_WITHIN(1e-5f, 3.12f, floor_mps);
    TEST_ASSERT_TRUE(rw_tov_guard_setpoint_allowed(&guard, floor_mps));
    TEST_ASSERT_TRUE(rw_tov_guard_setpoint_allowed(&guard, 10.0f));
    TEST_ASSERT_FALSE(rw_tov_guard_setpoint_allowed(&guard, nextafterf(floor_mps, 0.0f)));
    TEST_ASSERT_FALSE(rw_tov_guard_setpoint_allowed(&guard, 2.6f));
    TEST_ASSERT_FALSE(rw_tov_guard_setpoint_allowed(&guard, NAN));
    TEST_ASSERT_FALSE(rw_tov_guard_setpoint_allowed(&guard, INFINITY));
}

static void test_collapse_fires_once_after_set_time(void)
{
    int first = 0;
    TEST_ASSERT_EQUAL_INT(0, run_steps(100, 5.0f, &first));
    TEST_ASSERT_EQUAL_INT(1, run_steps(1000, 1.0f, &first));
    TEST_ASSERT_INT_WITHIN(1, 250, first); /* 0.25 s at 1 ms; float accumulation may add one tick */
    TEST_ASSERT_TRUE(first >= 250);        /* never before the set time */
    TEST_ASSERT_TRUE(rw_tov_guard_is_collapsed(&guard));
}

static void test_short_dips_never_fire(void)
{
    int first = 0;
    for (int i = 0; i < 10; ++i) {
        TEST_ASSERT_EQUAL_INT(0, run_steps(240, 2.0f, &first));
        TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, 2.6f, DT_S));
    }
}

static void test_rearms_after_recovery(void)
{
    int first = 0;
    TEST_ASSERT_EQUAL_INT(1, run_steps(400, 1.0f, &first));
    TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, 3.0f, DT_S));
    TEST_ASSERT_FALSE(rw_tov_guard_is_collapsed(&guard));
    TEST_ASSERT_EQUAL_INT(1, run_steps(400, 1.0f, &first));
    TEST_ASSERT_TRUE(first >= 250 && first <= 251);
}

static void test_nan_speed_and_bad_dt_ignored(void)
{
    guard.cfg.collapse_time_s = 0.01f;
    rw_tov_guard_prepare(&guard); /* a changed config is prepared */
    int first = 0;
    TEST_ASSERT_EQUAL_INT(0, run_steps(5, 1.0f, &first));
    TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, NAN, DT_S));
    TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, 1.0f, 0.0f));
    TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, 1.0f, -1.0f));
    TEST_ASSERT_FALSE(rw_tov_guard_step(&guard, 1.0f, NAN));
    TEST_ASSERT_EQUAL_INT(1, run_steps(10, 1.0f, &first));
    TEST_ASSERT_TRUE(first >= 5 && first <= 6);
}

static void test_invalid_config_never_reports(void)
{
    guard.cfg.margin = 0.5f;
    rw_tov_guard_prepare(&guard);
    int first = 0;
    TEST_ASSERT_FALSE(rw_tov_guard_setpoint_allowed(&guard, 100.0f));
    TEST_ASSERT_EQUAL_INT(0, run_steps(1000, 0.0f, &first));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_setpoint_floor_is_tov_times_margin);
    RUN_TEST(test_collapse_fires_once_after_set_time);
    RUN_TEST(test_short_dips_never_fire);
    RUN_TEST(test_rearms_after_recovery);
    RUN_TEST(test_nan_speed_and_bad_dt_ignored);
    RUN_TEST(test_invalid_config_never_reports);
    return UNITY_END();
}
