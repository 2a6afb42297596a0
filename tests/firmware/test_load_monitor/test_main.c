/*
 * Unity tests of rw_load_monitor (the load-loss detector of the rope drive): the force scale of the
 * reference rig (12 N/V), a vanishing load reported once after time_s, drops under the threshold or shorter
 * than time_s ignored, a slow fade ignored, nothing judged while not steady or settling, off at drop_n 0,
 * a fast battery sag followed by the integral no change (and a load loss without the voltage filter),
 * bad inputs never report. Run with `pio test -e native`.
 */
#include <math.h>
#include <stdbool.h>
#include <unity.h>

#include "rw_load_monitor.h"

#define DT_S 0.002f
#define BATTERY_V 12.0f

static rw_load_monitor mon;

void setUp(void)
{
    rw_load_monitor_config cfg;
    rw_load_monitor_config_defaults(&cfg);
    rw_load_monitor_init(&mon, &cfg);
}

void tearDown(void) {}

/* Steps force_n (rope force, N) for seconds as the core would feed it; returns how many steps reported. */
static int hold(float force_n, float seconds, bool steady, float battery_v)
{
    int fired = 0;
    int steps = (int)(seconds / DT_S + 0.5f);
    for (int i = 0; i < steps; ++i) {
        float integral = force_n / (mon.cfg.n_per_v * battery_v);
        fired += rw_load_monitor_step(&mon, steady, integral, battery_v, DT_S) ? 1 : 0;
    }
    return fired;
}

static void test_force_scale_of_the_reference_rig(void)
{
    TEST_ASSERT_FLOAT_WITHIN(0.01f, 11.98f, rw_load_monitor_n_per_v(2.0f, 1250.0f, 0.085f, 0.015f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_load_monitor_n_per_v(2.0f, 1250.0f, 0.0f, 0.015f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_load_monitor_n_per_v(2.0f, NAN, 0.085f, 0.015f));
    TEST_ASSERT_TRUE(rw_load_monitor_config_is_valid(&mon.cfg));
    TEST_ASSERT_EQUAL_FLOAT(1.0f, mon.cfg.drop_n);
}

static void test_a_vanishing_load_is_reported_once_after_the_set_time(void)
{
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 1.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 2.0f, true, BATTERY_V)); /* a 5 N load comes on */
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 0.098f, true, BATTERY_V)); /* it vanishes: not yet 0.1 s */
    TEST_ASSERT_EQUAL_INT(1, hold(1.6f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_FLOAT_WITHIN(0.3f, 4.8f, rw_load_monitor_drop_n(&mon));
}

static void test_small_or_short_drops_are_not_losses(void)
{
    TEST_ASSERT_EQUAL_INT(0, hold(2.5f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 2.0f, true, BATTERY_V)); /* 0.9 N: under drop_n */
    TEST_ASSERT_EQUAL_INT(0, hold(6.0f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(1.0f, 0.02f, true, BATTERY_V)); /* a 20 ms dip */
    TEST_ASSERT_EQUAL_INT(0, hold(6.0f, 2.0f, true, BATTERY_V));
}

static void test_a_slow_fade_is_not_a_loss(void)
{
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 2.0f, true, BATTERY_V));
    int fired = 0;
    for (int i = 0; i < 10000; ++i) { /* 5 N to 0 over 20 s */
        fired += hold(6.6f - 5.0f * (float)i / 10000.0f, DT_S, true, BATTERY_V);
    }
    TEST_ASSERT_EQUAL_INT(0, fired);
}

static void test_nothing_is_judged_while_not_steady_or_settling(void)
{
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 1.0f, false, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 0.2f, true, BATTERY_V)); /* settling */
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 0.25f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 1.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(1, hold(1.6f, 0.3f, true, BATTERY_V));
}

static void test_off_at_zero_threshold(void)
{
    mon.cfg.drop_n = 0.0f;
    rw_load_monitor_prepare(&mon, DT_S); /* a changed config is prepared */
    TEST_ASSERT_EQUAL_INT(0, hold(20.0f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_EQUAL_INT(0, hold(0.0f, 2.0f, true, BATTERY_V));
}

/* 7.5 N held while the battery steps 12 V -> 9.4 V for 0.5 s and back; the integral follows as the PI does
 * (first order, 0.3 s). Returns how many steps reported. */
static int sag_run(void)
{
    float n = mon.cfg.n_per_v;
    float integral = 7.5f / (n * 12.0f);
    float alpha = DT_S / (0.3f + DT_S);
    int fired = 0;
    for (int k = 0; k < 3000; ++k) {
        float v = (k >= 1500 && k < 1750) ? 9.4f : 12.0f;
        integral += alpha * (7.5f / (n * v) - integral);
        fired += rw_load_monitor_step(&mon, true, integral, v, DT_S) ? 1 : 0;
    }
    return fired;
}

static void test_a_fast_battery_sag_is_no_load_change(void)
{
    TEST_ASSERT_EQUAL_INT(0, sag_run());
    rw_load_monitor_reset(&mon);
    mon.cfg.battery_tau_s = 0.0f; /* the instantaneous voltage reads the sag as a load loss */
    rw_load_monitor_prepare(&mon, DT_S);
    TEST_ASSERT_EQUAL_INT(1, sag_run());
}

static void test_bad_inputs_never_report(void)
{
    TEST_ASSERT_EQUAL_INT(0, hold(6.6f, 2.0f, true, BATTERY_V));
    TEST_ASSERT_FALSE(rw_load_monitor_step(&mon, true, NAN, BATTERY_V, DT_S));
    TEST_ASSERT_FALSE(rw_load_monitor_step(&mon, true, 0.01f, INFINITY, DT_S));
    TEST_ASSERT_FALSE(rw_load_monitor_step(&mon, true, 0.01f, BATTERY_V, 0.0f));
    TEST_ASSERT_EQUAL_INT(0, hold(1.6f, 0.4f, true, BATTERY_V)); /* restarted: learning again */
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_force_scale_of_the_reference_rig);
    RUN_TEST(test_a_vanishing_load_is_reported_once_after_the_set_time);
    RUN_TEST(test_small_or_short_drops_are_not_losses);
    RUN_TEST(test_a_slow_fade_is_not_a_loss);
    RUN_TEST(test_nothing_is_judged_while_not_steady_or_settling);
    RUN_TEST(test_off_at_zero_threshold);
    RUN_TEST(test_a_fast_battery_sag_is_no_load_change);
    RUN_TEST(test_bad_inputs_never_report);
    return UNITY_END();
}
