/*
 * Unity tests of rw_multiturn (multi-turn angle of the AX-12A from its single-turn register).
 * Run with `pio test -e native`.
 *
 * A simulated servo drives it: the true angle advances at a set speed; the register is angle x 1023 / 300
 * with reading noise in 0..300 degrees and garbage (uniform 0..1023) in the 60 degree dead zone; the
 * present speed is quantised to 0.111 rpm.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <unity.h>

#include "rw_ax12.h"
#include "rw_multiturn.h"

#define DT_S 0.01f
#define TRACK_TOL_DEG 2.0f
#define GARBAGE (-1)

typedef struct {
    float start_deg;
    float speed_deg_s;
    float angle_deg;
    uint32_t rng;
    int dead_zone_reads; /* GARBAGE: uniform random register; else this fixed register value */
    long steps;
} sim_servo;

typedef struct {
    float max_err_deg;
    float max_err_dead_deg;
    float max_err_clear_deg; /* where the truth is clear of the dead zone: 20..280 degrees */
    int garbage_taken; /* steps where a dead-zone reading moved the estimate */
    long first_valid_step;
} track_result;

static rw_multiturn mt;

/* The tests speak degrees, deg/s and seconds; rw_multiturn takes ticks, ticks/ms Q10 and milliseconds
 * (rw_ax12.h): converted here, rounded to the nearest unit (0.000115 degrees, 0.000112 deg/s, 1 ms). */
static float step_deg(rw_multiturn *m, bool valid, float position_deg, float speed_deg_s, float dt_s)
{
    const int32_t position_ticks = (int32_t)lroundf(position_deg * RW_AX12_TICKS_PER_DEG);
    const int32_t speed_q10 = (int32_t)lroundf(speed_deg_s * RW_AX12_TICKS_PER_DEG * (1024.0f / 1000.0f));
    const uint32_t dt_ms = (uint32_t)lroundf(dt_s * 1000.0f);
    (void)rw_multiturn_step(m, valid, position_ticks, speed_q10, dt_ms);
    return rw_multiturn_angle_deg(m);
}

void setUp(void)
{
    rw_multiturn_config cfg;
    rw_multiturn_config_defaults(&cfg);
    rw_multiturn_init(&mt, &cfg);
}

void tearDown(void) {}

static uint32_t next_rand(sim_servo *s)
{
    s->rng = s->rng * 1664525u + 1013904223u;
    return s->rng >> 8; /* 24 bits */
}

static float uniform01(sim_servo *s)
{
    return (float)next_rand(s) / 16777216.0f;
}

static void servo_init(sim_servo *s, float start_deg, float rpm, uint32_t seed, int dead_zone_reads)
{
    s->start_deg = start_deg;
    s->speed_deg_s = rpm * 6.0f;
    s->angle_deg = start_deg;
    s->rng = seed * 2654435761u + 1u;
    s->dead_zone_reads = dead_zone_reads;
    s->steps = 0;
}

static float wrap360(float deg)
{
    float w = fmodf(deg, 360.0f);
    return w < 0.0f ? w + 360.0f : w;
}

static bool servo_in_dead_zone(const sim_servo *s)
{
    return wrap360(s->angle_deg) >= 300.0f;
}

static void servo_advance(sim_servo *s)
{
    ++s->steps;
    s->angle_deg = s->start_deg + s->speed_deg_s * DT_S * (float)s->steps; /* no accumulated rounding */
}

static float servo_position_deg(sim_servo *s)
{
    const float a = wrap360(s->angle_deg);
    long raw;
    if (a < 300.0f) {
        /* about 0.6 register units of noise (sum of three uniforms) */
        const float noise = (uniform01(s) + uniform01(s) + uniform01(s) - 1.5f) * 1.2f;
        raw = lroundf(a * 1023.0f / 300.0f + noise);
        raw = raw < 0 ? 0 : (raw > 1023 ? 1023 : raw);
    } else {
        raw = s->dead_zone_reads == GARBAGE ? (long)(next_rand(s) % 1024u) : s->dead_zone_reads;
    }
    return rw_ax12_position_deg((uint16_t)raw);
}

static float servo_speed_measured(const sim_servo *s)
{
    long units = lroundf(fabsf(s->speed_deg_s) / 6.0f / 0.111f);
    units = units > 1023 ? 1023 : units;
    return rw_ax12_speed_deg_s((uint16_t)((uint16_t)units | (s->speed_deg_s < 0.0f ? RW_AX12_DIRECTION_BIT : 0u)));
}

/* Runs `steps` steps; errors are measured from step `from` on, against truth + offset_deg. */
static track_result track(sim_servo *s, long steps, float dead_zone_speed_scale, long from, float offset_deg)
{
    track_result r = {0.0f, 0.0f, 0.0f, 0, -1};
    for (long k = 0; k < steps; ++k) {
        servo_advance(s);
        const bool dead = servo_in_dead_zone(s);
        float speed = servo_speed_measured(s);
        if (dead) {
            speed *= dead_zone_speed_scale;
        }
        const float before = rw_multiturn_angle_deg(&mt);
        const bool was_initialized = mt.state.initialized;
        const float est = step_deg(&mt, true, servo_position_deg(s), speed, DT_S);
        if (!dead && r.first_valid_step < 0) {
            r.first_valid_step = k;
        }
        if (dead && was_initialized && fabsf(est - (before + speed * DT_S)) > 1e-3f) {
            ++r.garbage_taken;
        }
        if (k >= from) {
            const float err = fabsf(est - s->angle_deg - offset_deg);
            r.max_err_deg = fmaxf(r.max_err_deg, err);
            if (dead) {
                r.max_err_dead_deg = fmaxf(r.max_err_dead_deg, err);
            }
            const float w = wrap360(s->angle_deg);
            if (w >= 20.0f && w <= 280.0f) {
                r.max_err_clear_deg = fmaxf(r.max_err_clear_deg, err);
            }
        }
    }
    return r;
}

static long steps_for_turns(float turns, float rpm)
{
    return lroundf(turns * 60.0f / rpm / DT_S);
}

static void check_twenty_turns(float rpm)
{
    for (int dir = -1; dir <= 1; dir += 2) {
        setUp();
        sim_servo s;
        servo_init(&s, 150.0f, (float)dir * rpm, 7u, GARBAGE);
        const track_result r = track(&s, steps_for_turns(20.5f, rpm), 1.0f, 0, 0.0f);
        TEST_ASSERT_TRUE(fabsf(s.angle_deg - s.start_deg) >= 20.0f * 360.0f);
        TEST_ASSERT_TRUE_MESSAGE(r.max_err_deg < TRACK_TOL_DEG, "tracks within two degrees");
        TEST_ASSERT_EQUAL_INT_MESSAGE(0, r.garbage_taken, "dead-zone garbage never taken");
        TEST_ASSERT_EQUAL_UINT16_MESSAGE(0u, mt.state.rejected, "a real move is never rejected");
    }
}

static void test_twenty_turns_at_5_rpm(void)
{
    check_twenty_turns(5.0f);
}

static void test_twenty_turns_at_20_rpm(void)
{
    check_twenty_turns(20.0f);
}

static void test_twenty_turns_at_59_rpm(void)
{
    check_twenty_turns(59.0f);
}

static void test_wrong_speed_in_the_dead_zone_is_resynchronised(void)
{
    const float rpms[] = {5.0f, 20.0f, 59.0f};
    const float scales[] = {1.08f, 0.9f};
    for (unsigned i = 0; i < 3u; ++i) {
        for (unsigned j = 0; j < 2u; ++j) {
            for (int dir = -1; dir <= 1; dir += 2) {
                setUp();
                sim_servo s;
                servo_init(&s, 150.0f, (float)dir * rpms[i], 3u, GARBAGE);
                const track_result r = track(&s, steps_for_turns(3.2f, rpms[i]), scales[j], 0, 0.0f);
                TEST_ASSERT_TRUE(r.max_err_dead_deg > 3.0f); /* the wrong speed did show */
                TEST_ASSERT_TRUE(r.max_err_dead_deg < 60.0f * 0.1f + 1.0f);
                TEST_ASSERT_EQUAL_INT(0, r.garbage_taken);
                TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
                TEST_ASSERT_TRUE_MESSAGE(r.max_err_clear_deg < TRACK_TOL_DEG, "re-synchronised after the dead zone");
            }
        }
    }
}

static void test_ten_percent_overestimate_takes_no_garbage(void)
{
    /* a 10 % speed overestimate drifts 6 degrees over the 60 degree zone: the 10 degree margin covers it */
    int taken = 0;
    for (uint32_t seed = 0u; seed < 6u; ++seed) {
        for (int dir = -1; dir <= 1; dir += 2) {
            setUp();
            sim_servo s;
            servo_init(&s, 150.0f, (float)dir * 20.0f, seed, GARBAGE);
            taken += track(&s, steps_for_turns(20.5f, 20.0f), 1.1f, 0, 0.0f).garbage_taken;
        }
    }
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, taken, "dead-zone garbage taken at a +10 % speed error");
}

static void test_single_impossible_jump_is_rejected_and_counted(void)
{
    sim_servo s;
    servo_init(&s, 100.0f, 20.0f, 11u, GARBAGE);
    (void)track(&s, 50, 1.0f, 0, 0.0f);
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
    servo_advance(&s);
    const float before = rw_multiturn_angle_deg(&mt);
    const float speed = servo_speed_measured(&s);
    const float out = step_deg(&mt, true, wrap360(s.angle_deg + 90.0f), speed, DT_S);
    TEST_ASSERT_EQUAL_UINT16(1u, mt.state.rejected);
    TEST_ASSERT_FLOAT_WITHIN(1e-3f, before + speed * DT_S, out);
    const track_result r = track(&s, 100, 1.0f, 0, 0.0f);
    TEST_ASSERT_TRUE(r.max_err_deg < TRACK_TOL_DEG);
    TEST_ASSERT_EQUAL_UINT16(1u, mt.state.rejected);
}

/* A still servo read RW_MULTITURN_AGREE times: the first reference is taken there. */
static void reference_at(float position_deg)
{
    for (unsigned i = 0u; i < RW_MULTITURN_AGREE; ++i) {
        (void)step_deg(&mt, true, position_deg, 0.0f, DT_S);
    }
    TEST_ASSERT_TRUE(mt.state.initialized);
}

static void test_jump_limit_edges(void)
{
    const float limit = mt.cfg.max_jump_deg;
    reference_at(100.0f);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 100.0f + limit - 0.5f, step_deg(&mt, true, 100.0f + limit - 0.5f, 0.0f, DT_S));
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 100.0f + limit - 0.5f,
                             step_deg(&mt, true, 100.0f + 2.0f * limit + 1.0f, 0.0f, DT_S));
    TEST_ASSERT_EQUAL_UINT16(1u, mt.state.rejected);
}

static void test_start_in_the_dead_zone_dead_reckons_until_a_usable_reading(void)
{
    sim_servo s;
    servo_init(&s, 320.0f, 20.0f, 5u, 1023); /* the register reads its end value in the dead zone */
    servo_advance(&s);
    const float first = step_deg(&mt, true, servo_position_deg(&s), servo_speed_measured(&s), DT_S);
    TEST_ASSERT_FALSE(mt.state.initialized);
    TEST_ASSERT_TRUE(mt.state.dead_reckoning);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, servo_speed_measured(&s) * DT_S, first);
    (void)track(&s, 100, 1.0f, 0, 0.0f); /* 12 degrees past the zone: referenced */
    TEST_ASSERT_TRUE(mt.state.initialized);
    const float offset = rw_multiturn_angle_deg(&mt) - s.angle_deg;
    TEST_ASSERT_TRUE(fabsf(offset - 360.0f * roundf(offset / 360.0f)) < TRACK_TOL_DEG);
    const track_result r = track(&s, steps_for_turns(10.0f, 20.0f), 1.0f, 0, offset);
    TEST_ASSERT_TRUE_MESSAGE(r.max_err_deg < TRACK_TOL_DEG, "then tracks ten turns");
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
}

static void test_power_up_in_the_dead_zone_never_references_garbage(void)
{
    /* the first reference needs RW_MULTITURN_AGREE readings that agree: dead-zone garbage never does */
    int lost = 0;
    for (uint32_t seed = 1u; seed <= 3u; ++seed) {
        setUp();
        sim_servo s;
        servo_init(&s, 330.0f, 20.0f, seed, GARBAGE);
        (void)track(&s, 100, 1.0f, 0, 0.0f); /* out of the zone by now */
        const float offset = rw_multiturn_angle_deg(&mt) - s.angle_deg;
        const float off_turn = fabsf(offset - 360.0f * roundf(offset / 360.0f));
        const track_result r = track(&s, steps_for_turns(3.0f, 20.0f), 1.0f, 0, offset);
        lost += (off_turn >= TRACK_TOL_DEG || r.max_err_deg >= TRACK_TOL_DEG) ? 1 : 0;
    }
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, lost, "power-up in the dead zone lost the reference");
}

static void test_no_answer_dead_reckons(void)
{
    reference_at(100.0f);
    TEST_ASSERT_TRUE(mt.state.initialized);
    TEST_ASSERT_FALSE(mt.state.dead_reckoning);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 106.0f, step_deg(&mt, false, 250.0f, 60.0f, 0.1f));
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
}

/* Integer inputs cannot be NaN; out-of-range ones are bounded: a position outside the register range is
 * no reading, a speed beyond RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10 is clamped to it, and a long gap
 * (int64 path) integrates exactly what the same time in short steps does. */
static void test_out_of_range_input_is_bounded(void)
{
    (void)step_deg(&mt, true, 100.0f, 0.0f, DT_S);
    const int32_t start = mt.state.angle_ticks;
    (void)rw_multiturn_step(&mt, true, -5, 0, 10u);
    (void)rw_multiturn_step(&mt, true, RW_AX12_TICKS_VALID_RANGE + 1, 0, 10u);
    TEST_ASSERT_EQUAL_INT32(start, mt.state.angle_ticks);
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
    (void)rw_multiturn_step(&mt, false, 0, INT32_MAX, 10u);
    TEST_ASSERT_EQUAL_INT32(start + 10 * (RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10 >> 10), mt.state.angle_ticks);
    (void)rw_multiturn_step(&mt, false, 0, INT32_MIN, 10u);
    TEST_ASSERT_EQUAL_INT32(start, mt.state.angle_ticks);
    /* 60 s without an answer at 59 rpm (532 units), once and in 10 ms steps: the same angle (59 turns), no drift */
    rw_multiturn other = mt;
    const int32_t speed_q10 = rw_ax12_speed_ticks_per_ms_q10(532u); /* 59 rpm */
    (void)rw_multiturn_step(&mt, false, 0, speed_q10, 60000u);
    for (int k = 0; k < 6000; ++k) {
        (void)rw_multiturn_step(&other, false, 0, speed_q10, 10u);
    }
    TEST_ASSERT_EQUAL_INT32(other.state.angle_ticks, mt.state.angle_ticks);
    /* 532 units = 354.3 deg/s; the Q10 speed unit is 0.0075 % slow: 1.6 degrees over these 59 turns */
    TEST_ASSERT_FLOAT_WITHIN(2.0f, 532.0f * 0.666f * 60.0f, rw_multiturn_angle_deg(&mt) - 100.0f);
}

static void test_reset_forgets_the_reference(void)
{
    reference_at(100.0f);
    (void)step_deg(&mt, true, 250.0f, 0.0f, DT_S);
    TEST_ASSERT_EQUAL_UINT16(1u, mt.state.rejected);
    rw_multiturn_reset(&mt);
    TEST_ASSERT_FALSE(mt.state.initialized);
    TEST_ASSERT_EQUAL_UINT16(0u, mt.state.rejected);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 250.0f, step_deg(&mt, true, 250.0f, 0.0f, DT_S));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_twenty_turns_at_5_rpm);
    RUN_TEST(test_twenty_turns_at_20_rpm);
    RUN_TEST(test_twenty_turns_at_59_rpm);
    RUN_TEST(test_wrong_speed_in_the_dead_zone_is_resynchronised);
    RUN_TEST(test_ten_percent_overestimate_takes_no_garbage);
    RUN_TEST(test_single_impossible_jump_is_rejected_and_counted);
    RUN_TEST(test_jump_limit_edges);
    RUN_TEST(test_start_in_the_dead_zone_dead_reckons_until_a_usable_reading);
    RUN_TEST(test_power_up_in_the_dead_zone_never_references_garbage);
    RUN_TEST(test_no_answer_dead_reckons);
    RUN_TEST(test_out_of_range_input_is_bounded);
    RUN_TEST(test_reset_forgets_the_reference);
    return UNITY_END();
}
