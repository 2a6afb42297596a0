/*
 * Unity tests of rw_mt_speed_estimator (M/T speed from edge count and edge timestamps).
 * A simulated encoder (integer nanoseconds, constant speed, 64 edges/rev) is sampled at the 1 ms
 * firmware tick; counts and microsecond clocks are uint32 and wrap. Run with `pio test -e native`.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_mt_speed_estimator.h"

#define CPR 64u
#define TICK_US 1000u
#define TIMEOUT_US 100000u

static rw_mt_speed_estimator est;

/* Encoder at constant speed: edge i at phase_ns + i * period_ns (i >= 0). */
typedef struct {
    uint64_t period_ns;
    uint64_t phase_ns;
    uint32_t count_offset;
    uint32_t time_offset_us;
} sim_encoder;

static sim_encoder sim_at_rpm(float rpm, uint32_t count_offset, uint32_t time_offset_us)
{
    const sim_encoder s = {
        .period_ns = (uint64_t)(60.0e9f / (rpm * (float)CPR) + 0.5f),
        .phase_ns = 123457u,
        .count_offset = count_offset,
        .time_offset_us = time_offset_us,
    };
    return s;
}

/* Captures count and last-edge time at t_ns, and steps the estimator; returns raw rev/s. */
static float sample(const sim_encoder *s, uint64_t t_ns)
{
    uint32_t count = s->count_offset;
    uint32_t edge_us = s->time_offset_us;
    if (t_ns >= s->phase_ns) {
        const uint64_t n = (t_ns - s->phase_ns) / s->period_ns + 1u; /* edges so far */
        count = (uint32_t)(s->count_offset + n);
        edge_us = (uint32_t)(s->time_offset_us + (s->phase_ns + (n - 1u) * s->period_ns) / 1000u);
    }
    const uint32_t now_us = (uint32_t)(s->time_offset_us + t_ns / 1000u);
    rw_mt_speed_estimator_step(&est, count, edge_us, now_us, 0.001f);
    return rw_mt_speed_estimator_raw_rev_per_s(&est);
}

/* Largest relative error of raw and filtered speed over ticks 60..300 at constant rpm. */
static float max_rel_error(float rpm, uint32_t count_offset, uint32_t time_offset_us)
{
    const sim_encoder s = sim_at_rpm(rpm, count_offset, time_offset_us);
    const float truth = rpm / 60.0f;
    float worst = 0.0f;
    for (uint32_t k = 1; k <= 300u; ++k) {
        const float raw = sample(&s, (uint64_t)k * TICK_US * 1000u);
        if (k >= 60u) {
            const float e_raw = fabsf(raw / truth - 1.0f);
            const float e_filt = fabsf(rw_mt_speed_estimator_rev_per_s(&est) / truth - 1.0f);
            worst = fmaxf(worst, fmaxf(e_raw, e_filt));
            TEST_ASSERT_FALSE(rw_mt_speed_estimator_is_stale(&est));
        }
    }
    return worst;
}

void setUp(void)
{
    rw_mt_speed_estimator_config cfg;
    rw_mt_speed_estimator_config_defaults(&cfg);
    cfg.timeout_us = TIMEOUT_US;
    cfg.filter_tau_s = 0.005f;
    rw_mt_speed_estimator_init(&est, &cfg);
}

void tearDown(void) {}

static void test_error_under_one_percent_1650_to_15000_rpm(void)
{
    const float rpms[] = {1000.0f, 1650.0f, 3000.0f, 8000.0f, 15000.0f};
    for (unsigned i = 0; i < sizeof rpms / sizeof rpms[0]; ++i) {
        rw_mt_speed_estimator_reset(&est);
        TEST_ASSERT_TRUE(max_rel_error(rpms[i], 0u, 0u) < 0.01f);
    }
}

static void test_wrap_of_count_and_clock(void)
{
    /* count wraps after 400 edges (~0.12 s at 3000 rpm), the clock after 0.1 s */
    TEST_ASSERT_TRUE(max_rel_error(3000.0f, UINT32_MAX - 400u, UINT32_MAX - 100000u) < 0.01f);
}

static void test_wrap_between_two_steps_exact(void)
{
    rw_mt_speed_estimator_step(&est, UINT32_MAX - 7u, UINT32_MAX - 599u, UINT32_MAX - 499u, 0.001f);
    rw_mt_speed_estimator_step(&est, 8u, 400u, 450u, 0.001f); /* 16 edges in 1000 us */
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 250.0f, rw_mt_speed_estimator_raw_rev_per_s(&est));
}

static void test_rpm_and_rope_speed_units(void)
{
    est.cfg.filter_tau_s = 0.0f;
    rw_mt_speed_estimator_prepare(&est, 0.0f); /* a changed config is prepared */
    rw_mt_speed_estimator_step(&est, 1000u, 5000u, 5100u, 0.001f);
    const float rope_mps = rw_mt_speed_estimator_step(&est, 1016u, 7000u, 7050u, 0.001f);
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 125.0f, rw_mt_speed_estimator_rev_per_s(&est));
    TEST_ASSERT_FLOAT_WITHIN(0.01f, 7500.0f, rw_mt_speed_estimator_rpm(&est));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 2.0f * 3.14159265f * 0.015f * 125.0f, rope_mps);
}

static void test_stop_decays_then_zero_and_stale_after_timeout(void)
{
    est.cfg.filter_tau_s = 0.0f;
    rw_mt_speed_estimator_prepare(&est, 0.0f);
    /* 3000 rpm until the edge at 10,000 us, then silence */
    rw_mt_speed_estimator_step(&est, 0u, 0u, 500u, 0.001f);
    rw_mt_speed_estimator_step(&est, 32u, 10000u, 10010u, 0.001f); /* 32 edges / 10 ms: 50 rev/s */
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 50.0f, rw_mt_speed_estimator_raw_rev_per_s(&est));
    float prev = 50.0f;
    for (uint32_t now_us = 11000u; now_us <= 10000u + TIMEOUT_US; now_us += TICK_US) {
        rw_mt_speed_estimator_step(&est, 32u, 10000u, now_us, 0.001f);
        const float raw = rw_mt_speed_estimator_raw_rev_per_s(&est);
        const float bound = 1.0e6f / ((float)CPR * (float)(now_us - 10000u));
        TEST_ASSERT_TRUE(raw <= bound * 1.0001f);
        TEST_ASSERT_TRUE(raw <= prev);
        TEST_ASSERT_FALSE(rw_mt_speed_estimator_is_stale(&est));
        prev = raw;
    }
    rw_mt_speed_estimator_step(&est, 32u, 10000u, 10000u + TIMEOUT_US + 1000u, 0.001f);
    TEST_ASSERT_TRUE(rw_mt_speed_estimator_is_stale(&est));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_mt_speed_estimator_rope_mps(&est));
}

static void test_restart_after_stop_longer_than_half_the_clock_range(void)
{
    est.cfg.filter_tau_s = 0.0f;
    rw_mt_speed_estimator_prepare(&est, 0.0f);
    rw_mt_speed_estimator_step(&est, 0u, 1000u, 1000u, 0.001f);
    rw_mt_speed_estimator_step(&est, 8u, 2000u, 2010u, 0.001f);
    /* still for 40 minutes (> 2^31 us), stepped every 50 ms */
    uint32_t now_us = 2010u;
    for (uint32_t k = 0; k < 48000u; ++k) {
        now_us += 50000u;
        rw_mt_speed_estimator_step(&est, 8u, 2000u, now_us, 0.05f);
    }
    TEST_ASSERT_TRUE(rw_mt_speed_estimator_is_stale(&est));
    /* turns again at 3000 rpm (an edge every 312.5 us): the first edge only re-latches */
    const uint32_t first_edge_us = now_us + 100u;
    rw_mt_speed_estimator_step(&est, 9u, first_edge_us, first_edge_us + 50u, 0.001f);
    TEST_ASSERT_TRUE(rw_mt_speed_estimator_is_stale(&est));
    rw_mt_speed_estimator_step(&est, 12u, first_edge_us + 938u, first_edge_us + 1000u, 0.001f);
    TEST_ASSERT_FALSE(rw_mt_speed_estimator_is_stale(&est));
    TEST_ASSERT_FLOAT_WITHIN(30.0f, 3000.0f, rw_mt_speed_estimator_rpm(&est));
}

static void test_first_step_only_latches(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_mt_speed_estimator_step(&est, 1000u, 5000u, 5100u, 0.001f));
    TEST_ASSERT_TRUE(rw_mt_speed_estimator_is_stale(&est));
}

static void test_backward_count_keeps_estimate(void)
{
    est.cfg.filter_tau_s = 0.0f;
    rw_mt_speed_estimator_prepare(&est, 0.0f);
    rw_mt_speed_estimator_step(&est, 1000u, 5000u, 5100u, 0.001f);
    rw_mt_speed_estimator_step(&est, 1016u, 7000u, 7050u, 0.001f);
    rw_mt_speed_estimator_step(&est, 900u, 7400u, 7500u, 0.001f);
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, 125.0f, rw_mt_speed_estimator_raw_rev_per_s(&est));
}

/* The M/T quotient (integer long division on the core) is dn 1e6 / (cpr dT) in Q16.16 (rev/s to 1/65536),
 * developed to 14 significant bits at least (1.2e-4 relative, under the 5e-4 the 1 us timestamps resolve in
 * a 2 ms interval) and exact for whole rev/s, against the exact quotient computed here in 64 bits, for
 * edge counts and intervals across the whole range the integer path takes (saturated at 32768 rev/s). */
static void test_quotient_is_the_exact_division_to_its_resolution(void)
{
    const uint32_t dns[] = {1u, 2u, 3u, 7u, 13u, 64u, 500u, 1073u};
    const uint32_t dts[] = {1u, 3u, 97u, 250u, 999u, 1000u, 2000u, 4093u, 65521u, 99999u};
    for (unsigned i = 0u; i < sizeof dns / sizeof dns[0]; ++i) {
        for (unsigned j = 0u; j < sizeof dts / sizeof dts[0]; ++j) {
            setUp();
            const uint32_t t0 = 5000u;
            rw_mt_speed_estimator_step(&est, 100u, t0, t0, 0.001f);
            rw_mt_speed_estimator_step(&est, 100u + dns[i], t0 + dts[j], t0 + dts[j], 0.001f);
            const uint64_t num = (uint64_t)dns[i] * 1000000u * 65536u;
            const uint64_t den = (uint64_t)CPR * dts[j];
            const double exact = (double)num / (double)den;
            const int32_t got = est.state.raw_rev_per_s_q16;
            if (exact >= 2147483647.0) {
                TEST_ASSERT_EQUAL_INT32(INT32_MAX, got);
                continue;
            }
            const double tolerance = exact / 8192.0 > 0.5 ? exact / 8192.0 : 0.5;
            TEST_ASSERT_TRUE(fabs((double)got - exact) <= tolerance);
            if (num % (den * 65536u) == 0u && num / den < (8192u << 16)) {
                TEST_ASSERT_EQUAL_INT32((int32_t)(num / den), got); /* whole rev/s under 8192: exact */
            }
        }
    }
}

static void test_invalid_config_reads_zero(void)
{
    est.cfg.counts_per_rev = 0u;
    rw_mt_speed_estimator_prepare(&est, 0.0f);
    TEST_ASSERT_FALSE(rw_mt_speed_estimator_config_is_valid(&est.cfg));
    rw_mt_speed_estimator_step(&est, 0u, 0u, 10u, 0.001f);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_mt_speed_estimator_step(&est, 100u, 1000u, 1010u, 0.001f));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_error_under_one_percent_1650_to_15000_rpm);
    RUN_TEST(test_wrap_of_count_and_clock);
    RUN_TEST(test_wrap_between_two_steps_exact);
    RUN_TEST(test_rpm_and_rope_speed_units);
    RUN_TEST(test_stop_decays_then_zero_and_stale_after_timeout);
    RUN_TEST(test_restart_after_stop_longer_than_half_the_clock_range);
    RUN_TEST(test_first_step_only_latches);
    RUN_TEST(test_backward_count_keeps_estimate);
    RUN_TEST(test_invalid_config_reads_zero);
    RUN_TEST(test_quotient_is_the_exact_division_to_its_resolution);
    return UNITY_END();
}
