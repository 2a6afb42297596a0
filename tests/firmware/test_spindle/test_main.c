/*
 * Unity tests of rw_spindle (homing, guide position loop, retract, stall, silence, soft limits).
 * Run with `pio test -e native`.
 *
 * Two kinds of drive: a small servo model in this file (AX-12A wheel mode: drive fraction from the moving
 * speed register, linear torque-speed line, 20 ms lag, T8 lead screw, hard stops at 0 and the stroke,
 * rope resisting beyond a grasp point, dead-zone garbage in the position register) stepped every 10 ms
 * after the core as rw_core does (read, step, write); and hand-made readings where a law or a timing is
 * checked exactly.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <unity.h>

#include "rw_ax12.h"
#include "rw_spindle.h"

#define DT_S 0.01f
#define DT_MS 10u /* DT_S, as rw_spindle_step takes it */
#define LEAD_MM 8.0f
#define MM_PER_DEG (LEAD_MM / 360.0f)
#define W0_DEG_S (59.0f * 6.0f)
#define STALL_STEPS 30

typedef struct {
    float angle_deg; /* output angle; guide mm = (angle - home) * MM_PER_DEG */
    float home_angle_deg;
    float speed_deg_s;
    float torque_frac; /* output torque over the stall torque */
    float stroke_mm;
    float object_at_mm; /* < 0: nothing grasped; beyond it the rope resists 2 % of stall torque a mm */
    bool stalled;
    bool answering;
    bool switch_fitted;
    uint16_t moving_speed_raw;
    uint32_t rng;
} servo_model;

static rw_spindle sp;
static rw_spindle_config cfg;
static servo_model servo;
static int outcome_count[RW_SPINDLE_NO_ANSWER + 1];
static float t_s;

static void default_config(rw_spindle_config *c)
{
    c->lead_mm_per_rev = LEAD_MM;
    c->guide_min_mm = 0.0f;
    c->guide_max_mm = 180.0f;
    c->kp_per_s = 4.0f;
    c->max_speed_mmps = 6.0f;
    c->tolerance_mm = 0.5f;
    c->homing_speed_mmps = 3.0f;
    c->homing_load_pct = 25.0f;
    c->stall_load_pct = 50.0f;
    c->stall_time_s = 0.3f;
    c->secure_load_pct = 12.0f;
    c->retract_speed_mmps = 5.0f;
    c->timeout_s = 0.2f;
}

void setUp(void)
{
    default_config(&cfg);
    rw_spindle_init(&sp, &cfg);
    servo = (servo_model){.angle_deg = 120.0f, .home_angle_deg = 120.0f - 40.0f / MM_PER_DEG, .stroke_mm = 180.0f,
                          .object_at_mm = -1.0f, .answering = true, .rng = 12345u};
    for (int k = 0; k <= RW_SPINDLE_NO_ANSWER; ++k) {
        outcome_count[k] = 0;
    }
    t_s = 0.0f;
}

void tearDown(void) {}

static void reconfigure(void)
{
    rw_spindle_init(&sp, &cfg);
}

static float guide_mm(void)
{
    return (servo.angle_deg - servo.home_angle_deg) * MM_PER_DEG;
}

static uint32_t next_rand(void)
{
    servo.rng = servo.rng * 1664525u + 1013904223u;
    return servo.rng >> 8;
}

static uint16_t signed_raw(float value)
{
    long m = lroundf(fabsf(value));
    m = m > 1023 ? 1023 : m;
    return (uint16_t)((uint16_t)m | (value < 0.0f ? RW_AX12_DIRECTION_BIT : 0u));
}

static rw_spindle_reading servo_registers(void)
{
    rw_spindle_reading r;
    float a = fmodf(servo.angle_deg, 360.0f);
    a = a < 0.0f ? a + 360.0f : a;
    if (a < 300.0f) {
        const float noise = ((float)(next_rand() % 1000u) / 1000.0f - 0.5f) * 1.5f;
        long raw = lroundf(a * 1023.0f / 300.0f + noise);
        r.position_raw = (uint16_t)(raw < 0 ? 0 : (raw > 1023 ? 1023 : raw));
    } else {
        r.position_raw = (uint16_t)(next_rand() % 1024u); /* dead zone: garbage */
    }
    r.speed_raw = signed_raw(servo.speed_deg_s / (0.111f * 6.0f));
    r.load_raw = signed_raw(servo.torque_frac * 1000.0f);
    r.limit_switch = servo.switch_fitted && guide_mm() <= 1.0f;
    return r;
}

static void servo_step(float dt_s)
{
    const uint16_t raw = servo.moving_speed_raw;
    const float u = (float)(raw & RW_AX12_MAGNITUDE_MASK) / 1023.0f * ((raw & RW_AX12_DIRECTION_BIT) ? -1.0f : 1.0f);
    const float h = dt_s / 10.0f;
    const float alpha = 1.0f - expf(-h / 0.02f);
    for (int k = 0; k < 10; ++k) {
        const float pos = guide_mm();
        float load = servo.object_at_mm >= 0.0f && pos > servo.object_at_mm ? 0.02f * (pos - servo.object_at_mm) : 0.0f;
        float target = 0.0f;
        if (u != 0.0f && !servo.stalled) {
            target = W0_DEG_S * (u - load - (u > 0.0f ? 0.033f : -0.033f));
            target = u > 0.0f ? fmaxf(target, 0.0f) : fminf(target, 0.0f); /* self-locking screw */
        }
        servo.speed_deg_s += (target - servo.speed_deg_s) * alpha;
        servo.angle_deg += servo.speed_deg_s * h;
        const float p = guide_mm();
        if (p < 0.0f || p > servo.stroke_mm) { /* hard end stop */
            servo.angle_deg = servo.home_angle_deg + (p < 0.0f ? 0.0f : servo.stroke_mm) / MM_PER_DEG;
            servo.speed_deg_s = 0.0f;
        }
        servo.torque_frac = u != 0.0f ? u - servo.speed_deg_s / W0_DEG_S : 0.0f;
    }
}

/* One 10 ms period as rw_core runs it: read, step, write; then the servo moves. */
static rw_spindle_outcome tick(void)
{
    rw_spindle_reading r = servo_registers();
    const rw_spindle_outcome out = rw_spindle_step(&sp, servo.answering ? &r : NULL, DT_MS);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw & (uint16_t)~0x07FFu);
    servo.moving_speed_raw = sp.state.moving_speed_raw;
    servo_step(DT_S);
    t_s += DT_S;
    ++outcome_count[out];
    return out;
}

/* Ticks until `until` (returns true) or for `seconds` (returns false). */
static bool run_until(rw_spindle_outcome until, float seconds)
{
    const long n = lroundf(seconds / DT_S);
    for (long k = 0; k < n; ++k) {
        if (tick() == until) {
            return true;
        }
    }
    return false;
}

static void home_by_stall(void)
{
    rw_spindle_home(&sp);
    TEST_ASSERT_TRUE_MESSAGE(run_until(RW_SPINDLE_HOMED_BY_STALL, 30.0f), "homing by stall ended");
    for (int k = 0; k <= RW_SPINDLE_NO_ANSWER; ++k) {
        outcome_count[k] = 0;
    }
}

/* Hand-made reading: the servo still at register 500 unless told otherwise. */
static rw_spindle_reading reading(float speed_units, float load_permille, bool sw)
{
    rw_spindle_reading r = {500u, signed_raw(speed_units), signed_raw(load_permille), sw};
    return r;
}

static void homed_at_zero(void)
{
    rw_spindle_home(&sp);
    rw_spindle_reading r = reading(0.0f, 0.0f, true);
    TEST_ASSERT_EQUAL_INT(RW_SPINDLE_HOMED_BY_SWITCH, rw_spindle_step(&sp, &r, DT_MS));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, sp.state.position_mm);
}

static uint16_t raw_for_mmps(float mmps)
{
    return rw_ax12_moving_speed_raw(mmps / MM_PER_DEG);
}

static void test_homing_by_stall_finds_the_end_stop(void)
{
    rw_spindle_home(&sp);
    float at_stop_s = -1.0f;
    bool homed = false;
    for (long k = 0; k < 3000 && !homed; ++k) {
        if (at_stop_s < 0.0f && guide_mm() <= 0.0f) {
            at_stop_s = t_s;
        }
        const bool moving = sp.state.moving_speed_raw != 0u;
        homed = tick() == RW_SPINDLE_HOMED_BY_STALL;
        if (moving) {
            TEST_ASSERT_TRUE_MESSAGE(sp.state.moving_speed_raw == 0u || (sp.state.moving_speed_raw & RW_AX12_DIRECTION_BIT),
                                     "homing turns clockwise (towards home)");
        }
    }
    TEST_ASSERT_TRUE(homed);
    TEST_ASSERT_TRUE(at_stop_s > 0.0f);
    TEST_ASSERT_TRUE(t_s - at_stop_s >= 0.3f - DT_S && t_s - at_stop_s <= 0.4f);
    TEST_ASSERT_FLOAT_WITHIN(0.05f, 0.0f, guide_mm());
    TEST_ASSERT_TRUE(rw_spindle_is_homed(&sp));
    TEST_ASSERT_EQUAL_UINT8(RW_SPINDLE_IDLE, sp.state.mode);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    (void)run_until(RW_SPINDLE_NO_ANSWER, 1.0f);
    TEST_ASSERT_EQUAL_INT(1, outcome_count[RW_SPINDLE_HOMED_BY_STALL]);
    TEST_ASSERT_FLOAT_WITHIN(0.05f, guide_mm(), sp.state.position_mm);
}

static void test_homing_by_switch(void)
{
    servo.switch_fitted = true;
    rw_spindle_home(&sp);
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_HOMED_BY_SWITCH, 30.0f));
    TEST_ASSERT_TRUE(guide_mm() > 0.7f && guide_mm() <= 1.0f);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, sp.state.position_mm);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    TEST_ASSERT_EQUAL_INT(0, outcome_count[RW_SPINDLE_HOMED_BY_STALL]);
}

static void test_homing_stall_needs_load_and_stillness_for_the_stall_time(void)
{
    rw_spindle_home(&sp);
    rw_spindle_reading moving = reading(-200.0f, -400.0f, false);
    rw_spindle_reading light = reading(0.0f, -100.0f, false);
    rw_spindle_reading stalled = reading(0.0f, -400.0f, false);
    for (int k = 0; k < 200; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &moving, DT_MS));
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &light, DT_MS));
    }
    for (int k = 0; k < STALL_STEPS - 2; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &stalled, DT_MS));
    }
    TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &moving, DT_MS)); /* interrupted */
    int steps = 1;
    while (rw_spindle_step(&sp, &stalled, DT_MS) == RW_SPINDLE_NOTHING) {
        ++steps;
        TEST_ASSERT_TRUE(steps < 100);
    }
    TEST_ASSERT_INT_WITHIN(1, STALL_STEPS, steps);
    TEST_ASSERT_TRUE(rw_spindle_is_homed(&sp));
}

/* A step without a reading (a lost reply on the split bus) keeps the stall time held so far: homing ends after
 * stall_time_s of stalled readings, the missing steps neither restarting nor counting. */
static void test_homing_stall_keeps_its_time_through_missing_readings(void)
{
    rw_spindle_home(&sp);
    rw_spindle_reading stalled = reading(0.0f, -400.0f, false);
    for (int k = 0; k < STALL_STEPS / 2; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &stalled, DT_MS));
    }
    for (int k = 0; k < 3; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, NULL, DT_MS)); /* replies lost */
    }
    int steps = 1;
    while (rw_spindle_step(&sp, &stalled, DT_MS) == RW_SPINDLE_NOTHING) {
        ++steps;
        TEST_ASSERT_TRUE(steps < 100);
    }
    TEST_ASSERT_INT_WITHIN(1, STALL_STEPS - STALL_STEPS / 2, steps);
    TEST_ASSERT_TRUE(rw_spindle_is_homed(&sp));
}

static void test_homing_again_ends_at_the_stop(void)
{
    /* the soft limits do not apply while homing: re-homing drives to the stop and stalls there */
    home_by_stall();
    rw_spindle_move_to(&sp, 10.0f);
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_TARGET_REACHED, 10.0f));
    rw_spindle_home(&sp);
    TEST_ASSERT_TRUE_MESSAGE(run_until(RW_SPINDLE_HOMED_BY_STALL, 10.0f), "re-homing ends at the stop");
}

static void test_position_loop_is_p_law_saturated_and_zero_in_tolerance(void)
{
    const float targets[] = {0.4f, -0.4f, 0.5f, 0.6f, 1.0f, -1.2f, 1.6f, 10.0f, -40.0f};
    const float expected[] = {0.0f, 0.0f, 0.0f, 2.4f, 4.0f, -4.8f, 6.0f, 6.0f, -6.0f};
    cfg.guide_min_mm = -50.0f;
    for (unsigned i = 0; i < sizeof targets / sizeof targets[0]; ++i) {
        reconfigure();
        homed_at_zero();
        rw_spindle_move_to(&sp, targets[i]);
        rw_spindle_reading r = reading(0.0f, 0.0f, false);
        (void)rw_spindle_step(&sp, &r, DT_MS);
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, expected[i], ((float)sp.state.command_umps * 1.0e-3f));
        TEST_ASSERT_EQUAL_UINT16(raw_for_mmps(expected[i]), sp.state.moving_speed_raw);
        TEST_ASSERT_EQUAL(expected[i] < 0.0f, (sp.state.moving_speed_raw & RW_AX12_DIRECTION_BIT) != 0u);
    }
}

static void test_target_reached_once_per_target(void)
{
    homed_at_zero();
    rw_spindle_reading r = reading(0.0f, 0.0f, false);
    rw_spindle_move_to(&sp, 0.3f);
    int reached = 0;
    for (int k = 0; k < 100; ++k) {
        reached += rw_spindle_step(&sp, &r, DT_MS) == RW_SPINDLE_TARGET_REACHED;
    }
    TEST_ASSERT_EQUAL_INT(1, reached);
    rw_spindle_move_to(&sp, 0.2f);
    reached = 0;
    for (int k = 0; k < 100; ++k) {
        reached += rw_spindle_step(&sp, &r, DT_MS) == RW_SPINDLE_TARGET_REACHED;
    }
    TEST_ASSERT_EQUAL_INT(1, reached);
}

static void test_move_across_dead_zones_tracks_and_reports_once(void)
{
    home_by_stall();
    rw_spindle_move_to(&sp, 100.0f); /* 12.5 servo turns */
    float worst = 0.0f;
    for (long k = 0; k < 2500; ++k) {
        const float read_mm = guide_mm();
        (void)tick();
        worst = fmaxf(worst, fabsf(sp.state.position_mm - read_mm));
        TEST_ASSERT_TRUE((sp.state.moving_speed_raw & RW_AX12_MAGNITUDE_MASK) <= raw_for_mmps(6.0f));
    }
    TEST_ASSERT_EQUAL_INT(1, outcome_count[RW_SPINDLE_TARGET_REACHED]);
    TEST_ASSERT_FLOAT_WITHIN(0.55f, 100.0f, guide_mm());
    TEST_ASSERT_TRUE_MESSAGE(worst < 2.0f * MM_PER_DEG, "guide estimate within two degrees of the servo");
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.turns.state.rejected);
}

static void test_soft_limits_stop_outward_motion_only(void)
{
    rw_spindle_reading r = reading(0.0f, 0.0f, false);
    cfg.guide_min_mm = 0.0f;
    cfg.guide_max_mm = 10.0f;
    reconfigure();
    homed_at_zero();
    rw_spindle_move_to(&sp, -5.0f);
    (void)rw_spindle_step(&sp, &r, DT_MS);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    rw_spindle_move_to(&sp, 5.0f);
    (void)rw_spindle_step(&sp, &r, DT_MS);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 6.0f, ((float)sp.state.command_umps * 1.0e-3f));
    cfg.guide_min_mm = -10.0f;
    cfg.guide_max_mm = 0.0f;
    reconfigure();
    homed_at_zero();
    rw_spindle_move_to(&sp, 5.0f);
    (void)rw_spindle_step(&sp, &r, DT_MS);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    rw_spindle_retract(&sp);
    (void)rw_spindle_step(&sp, &r, DT_MS);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    rw_spindle_move_to(&sp, -5.0f);
    (void)rw_spindle_step(&sp, &r, DT_MS);
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, -6.0f, ((float)sp.state.command_umps * 1.0e-3f));
}

static void test_retract_secures_after_the_load_has_held(void)
{
    home_by_stall();
    servo.object_at_mm = 100.0f;
    rw_spindle_retract(&sp);
    int high_at_start = 0;
    for (int k = 0; k < 5; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, tick());
        high_at_start += sp.state.load_permille >= 120;
    }
    TEST_ASSERT_TRUE_MESSAGE(high_at_start > 0, "starting from rest loads the servo (the spike is there)");
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_SECURED, 40.0f));
    TEST_ASSERT_TRUE(guide_mm() > 100.0f && guide_mm() < 110.0f);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    TEST_ASSERT_EQUAL_UINT8(RW_SPINDLE_IDLE, sp.state.mode);
    TEST_ASSERT_EQUAL_INT(0, outcome_count[RW_SPINDLE_STALLED]);
}

static void test_retract_spike_shorter_than_the_stall_time_does_not_secure(void)
{
    homed_at_zero();
    rw_spindle_retract(&sp);
    rw_spindle_reading spike = reading(0.0f, 600.0f, false);
    rw_spindle_reading free_run = reading(200.0f, 30.0f, false);
    rw_spindle_reading pushed = reading(200.0f, -400.0f, false);
    rw_spindle_reading held = reading(5.0f, 130.0f, false);
    for (int k = 0; k < STALL_STEPS - 1; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &spike, DT_MS));
    }
    for (int k = 0; k < 100; ++k) {
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &free_run, DT_MS));
        TEST_ASSERT_EQUAL_INT(RW_SPINDLE_NOTHING, rw_spindle_step(&sp, &pushed, DT_MS));
    }
    TEST_ASSERT_EQUAL_UINT16(raw_for_mmps(5.0f), sp.state.moving_speed_raw); /* retract = counter-clockwise */
    int steps = 1;
    while (rw_spindle_step(&sp, &held, DT_MS) != RW_SPINDLE_SECURED) {
        ++steps;
        TEST_ASSERT_TRUE(steps < 100);
    }
    TEST_ASSERT_INT_WITHIN(1, STALL_STEPS, steps);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
}

static void test_retract_with_nothing_ends_at_the_stroke(void)
{
    cfg.guide_max_mm = 30.0f;
    reconfigure();
    home_by_stall();
    rw_spindle_retract(&sp);
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_STROKE_END, 20.0f));
    TEST_ASSERT_TRUE(sp.state.position_mm >= 30.0f);
    (void)run_until(RW_SPINDLE_NO_ANSWER, 1.0f);
    TEST_ASSERT_TRUE(guide_mm() >= 30.0f && guide_mm() < 30.3f);
    TEST_ASSERT_EQUAL_INT(1, outcome_count[RW_SPINDLE_STROKE_END]);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
}

/* guide_max on the hard stop (180 mm, the model's stroke): the stall on the stop is the stroke's end. */
static void test_retract_against_the_hard_stop_is_not_secured(void)
{
    home_by_stall();
    rw_spindle_retract(&sp);
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_STROKE_END, 60.0f));
    TEST_ASSERT_EQUAL_INT(0, outcome_count[RW_SPINDLE_SECURED]);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
}

static void test_blocked_guide_stalls_after_the_stall_time(void)
{
    home_by_stall();
    rw_spindle_move_to(&sp, 60.0f);
    while (guide_mm() < 20.0f) {
        (void)tick();
        TEST_ASSERT_TRUE(t_s < 30.0f);
    }
    servo.stalled = true;
    const float blocked_at = t_s;
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_STALLED, 3.0f));
    TEST_ASSERT_TRUE(t_s - blocked_at >= 0.3f && t_s - blocked_at <= 0.4f);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    TEST_ASSERT_EQUAL_UINT8(RW_SPINDLE_IDLE, sp.state.mode);
}

static void test_silent_servo_reported_once_after_the_timeout(void)
{
    home_by_stall();
    rw_spindle_move_to(&sp, 60.0f);
    (void)run_until(RW_SPINDLE_NO_ANSWER, 2.0f);
    servo.answering = false;
    const float silent_from = t_s;
    TEST_ASSERT_TRUE(run_until(RW_SPINDLE_NO_ANSWER, 1.0f));
    TEST_ASSERT_TRUE(t_s - silent_from >= 0.2f - 1e-4f && t_s - silent_from <= 0.2f + DT_S + 1e-4f);
    TEST_ASSERT_EQUAL_UINT16(0u, sp.state.moving_speed_raw);
    TEST_ASSERT_FALSE(sp.state.answering);
    (void)run_until(RW_SPINDLE_HOMED_BY_STALL, 2.0f);
    TEST_ASSERT_EQUAL_INT(1, outcome_count[RW_SPINDLE_NO_ANSWER]);
    servo.answering = true;
    (void)run_until(RW_SPINDLE_HOMED_BY_STALL, 0.5f);
    servo.answering = false;
    (void)run_until(RW_SPINDLE_HOMED_BY_STALL, 1.0f);
    TEST_ASSERT_EQUAL_INT(2, outcome_count[RW_SPINDLE_NO_ANSWER]);
}

static void test_command_register_never_exceeds_1023(void)
{
    cfg.max_speed_mmps = 1000.0f;
    cfg.homing_speed_mmps = 1000.0f;
    cfg.retract_speed_mmps = 1000.0f;
    cfg.kp_per_s = 1000.0f;
    cfg.guide_min_mm = -1000.0f;
    cfg.guide_max_mm = 1000.0f;
    rw_spindle_reading r = reading(300.0f, 0.0f, false);
    for (int mode = 0; mode < 4; ++mode) {
        reconfigure();
        homed_at_zero();
        switch (mode) {
        case 0: rw_spindle_home(&sp); break;
        case 1: rw_spindle_move_to(&sp, 500.0f); break;
        case 2: rw_spindle_move_to(&sp, -500.0f); break;
        default: rw_spindle_retract(&sp); break;
        }
        (void)rw_spindle_step(&sp, &r, DT_MS);
        TEST_ASSERT_EQUAL_UINT16(mode == 0 || mode == 2 ? 2047u : 1023u, sp.state.moving_speed_raw);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_homing_by_stall_finds_the_end_stop);
    RUN_TEST(test_homing_by_switch);
    RUN_TEST(test_homing_stall_needs_load_and_stillness_for_the_stall_time);
    RUN_TEST(test_homing_stall_keeps_its_time_through_missing_readings);
    RUN_TEST(test_homing_again_ends_at_the_stop);
    RUN_TEST(test_position_loop_is_p_law_saturated_and_zero_in_tolerance);
    RUN_TEST(test_target_reached_once_per_target);
    RUN_TEST(test_move_across_dead_zones_tracks_and_reports_once);
    RUN_TEST(test_soft_limits_stop_outward_motion_only);
    RUN_TEST(test_retract_secures_after_the_load_has_held);
    RUN_TEST(test_retract_spike_shorter_than_the_stall_time_does_not_secure);
    RUN_TEST(test_retract_with_nothing_ends_at_the_stroke);
    RUN_TEST(test_retract_against_the_hard_stop_is_not_secured);
    RUN_TEST(test_blocked_guide_stalls_after_the_stall_time);
    RUN_TEST(test_silent_servo_reported_once_after_the_timeout);
    RUN_TEST(test_command_register_never_exceeds_1023);
    return UNITY_END();
}
