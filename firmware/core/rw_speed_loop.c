/*
 * rw_speed_loop.c - the rope speed loop (estimator, ramp, PI + feed-forward, ESC pulse), Q16.16 fixed point.
 */
#include "rw_speed_loop.h"

#include "rw_defaults.h"
#include "rw_float_bits.h"

/* 1 / RW_SPEED_LOOP_GUARD_APPROACH_S and RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2 in Q16.16 */
#define RW_SPEED_LOOP_APPROACH_PER_S_Q16 ((int32_t)(65536.0f / RW_SPEED_LOOP_GUARD_APPROACH_S))
#define RW_SPEED_LOOP_APPROACH_MIN_Q16 ((int32_t)(RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2 * 65536.0f))
/* RW_ENCODER_HOLD_MIN_MMPS in m/s Q16.16 */
#define RW_SPEED_LOOP_HOLD_MIN_Q16 ((int32_t)(((int64_t)RW_ENCODER_HOLD_MIN_MMPS * 65536) / 1000))
#define RW_SPEED_LOOP_TWO_PI_F 6.2831853f
/* the stale bound in us m/s is kept in Q8 up to this (a 0.68 m wheel at one count per turn stays under it) */
#define RW_SPEED_LOOP_STALE_MAX_Q8 0xFFFFFF00u

void rw_speed_loop_init(rw_speed_loop *loop)
{
    rw_mt_speed_estimator_config est;
    rw_mt_speed_estimator_config_defaults(&est);
    rw_mt_speed_estimator_init(&loop->estimator, &est);
    rw_ramp_config ramp;
    rw_ramp_config_defaults(&ramp);
    rw_ramp_init(&loop->ramp, &ramp);
    rw_pi_controller_config pi;
    rw_pi_controller_config_defaults(&pi);
    rw_pi_controller_init(&loop->pi, &pi);
    rw_throttle_map_config thr;
    rw_throttle_map_config_defaults(&thr);
    rw_throttle_map_init(&loop->throttle, &thr);
    loop->cfg.guard_mps = RW_DEFAULT_TOV_MPS * RW_DEFAULT_TOV_MARGIN;
    loop->state.battery_v = 0.0f;
    rw_speed_loop_prepare(loop, 0.0f);
    rw_speed_loop_reset(loop);
}

/* RW_ENCODER_STALE_EDGE_PERIODS edge periods x rope speed, us m/s in Q8: N 2 pi r 1e6 / counts_per_rev (the
 * rope a wheel turn moves over the edges in it, times the microseconds in a second); 0 when not computable. */
static uint64_t stale_bound_q16(const rw_mt_speed_estimator_config *enc)
{
    if (enc->counts_per_rev == 0u || !rw_f32_positive_finite(enc->wheel_radius_m)) {
        return 0u;
    }
    const float bound_us_mps = (float)RW_ENCODER_STALE_EDGE_PERIODS * RW_SPEED_LOOP_TWO_PI_F * 1.0e6f *
                               enc->wheel_radius_m / (float)enc->counts_per_rev;
    const float q8 = bound_us_mps * 256.0f;
    const uint32_t bound_q8 = rw_f32_lt(q8, (float)RW_SPEED_LOOP_STALE_MAX_Q8) ? (uint32_t)q8 : RW_SPEED_LOOP_STALE_MAX_Q8;
    return (uint64_t)bound_q8 << 8;
}

void rw_speed_loop_prepare_estimator(rw_speed_loop *loop, float dt_s)
{
    rw_mt_speed_estimator_prepare(&loop->estimator, dt_s);
    loop->state.stale_bound_q16 = stale_bound_q16(&loop->estimator.cfg);
}

void rw_speed_loop_prepare_ramp(rw_speed_loop *loop, float dt_s)
{
    rw_ramp_prepare(&loop->ramp, dt_s);
}

void rw_speed_loop_prepare_pi(rw_speed_loop *loop, float dt_s)
{
    rw_pi_controller_prepare(&loop->pi, dt_s);
}

/* The throttle map keeps the battery voltage it was prepared for, which is always the loop's (both change
 * only in rw_speed_loop_set_battery, or in the feed-forward when they differ): one division, not two. */
void rw_speed_loop_prepare_throttle(rw_speed_loop *loop)
{
    rw_throttle_map_prepare(&loop->throttle);
}

void rw_speed_loop_prepare_guard(rw_speed_loop *loop)
{
    loop->state.guard_q16 = rw_f32_to_q16(loop->cfg.guard_mps);
}

void rw_speed_loop_prepare(rw_speed_loop *loop, float dt_s)
{
    rw_speed_loop_prepare_estimator(loop, dt_s);
    rw_speed_loop_prepare_ramp(loop, dt_s);
    rw_speed_loop_prepare_pi(loop, dt_s);
    rw_speed_loop_prepare_throttle(loop);
    rw_speed_loop_prepare_guard(loop);
}

void rw_speed_loop_set_battery(rw_speed_loop *loop, float battery_v)
{
    loop->state.battery_v = battery_v;
    rw_throttle_map_prepare_battery(&loop->throttle, battery_v);
}

float rw_speed_loop_measure(rw_speed_loop *loop, uint32_t counts, uint32_t edge_us, uint32_t now_us, float dt_s)
{
    return rw_mt_speed_estimator_step(&loop->estimator, counts, edge_us, now_us, dt_s);
}

void rw_speed_loop_reset(rw_speed_loop *loop)
{
    rw_pi_controller_set_out_min_q16(&loop->pi, 0);
    rw_pi_controller_reset(&loop->pi);
    rw_ramp_reset(&loop->ramp);
    loop->state.setpoint_q16 = 0;
    loop->state.pulse_us = loop->throttle.cfg.pulse_min_us;
    loop->state.pulse_third_us = (uint16_t)(3u * loop->throttle.cfg.pulse_min_us);
}

void rw_speed_loop_start(rw_speed_loop *loop)
{
    rw_pi_controller_reset(&loop->pi);
    rw_ramp_reset_to(&loop->ramp, rw_mt_speed_estimator_rope_mps(&loop->estimator));
}

/* The target the ramp steps towards while airborne: the setpoint falls onto the guard at
 * min(ramp_down_mps2, room / RW_SPEED_LOOP_GUARD_APPROACH_S + RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2),
 * room = setpoint - guard (the approach step, rate x dt, bounds the target; the ramp's own fall rate bounds it
 * further: the same min). A setpoint already under the guard (the guard raised in flight) falls at the minimum
 * approach rate. */
static int32_t airborne_target_q16(const rw_speed_loop *loop, int32_t target_q16, float dt_s)
{
    const int32_t ramp_q16 = rw_ramp_output_q16(&loop->ramp);
    if (target_q16 >= ramp_q16) {
        return target_q16;
    }
    const int64_t room_q16 = (int64_t)ramp_q16 - loop->state.guard_q16;
    const int32_t room_clamped_q16 = room_q16 > INT32_MAX / 4 ? INT32_MAX / 4 : (room_q16 < 0 ? 0 : (int32_t)room_q16);
    const int64_t approach_q16 =
        (rw_mul_s32_s64(room_clamped_q16, RW_SPEED_LOOP_APPROACH_PER_S_Q16) >> 16) + RW_SPEED_LOOP_APPROACH_MIN_Q16;
    const int64_t step_q16 = (rw_mul_s32_s64((int32_t)approach_q16, rw_f32_to_fixed(dt_s, 32u)) + 0x80000000) >> 32;
    return (int64_t)ramp_q16 - step_q16 > target_q16 ? (int32_t)(ramp_q16 - step_q16) : target_q16;
}

/* The reading is stale: the setpoint asks for a turning wheel (>= RW_ENCODER_HOLD_MIN_MMPS) and no edge came
 * for longer than RW_ENCODER_STALE_MIN_US and RW_ENCODER_STALE_EDGE_PERIODS edge periods at the setpoint,
 * i.e. silence x setpoint > the prepared bound (a product: no division on the tick). */
static bool encoder_stale(const rw_speed_loop *loop, int32_t setpoint_q16, uint32_t now_us)
{
    const uint32_t silence_us = now_us - loop->estimator.state.last_edge_us;
    if (silence_us <= RW_ENCODER_STALE_MIN_US || silence_us >= 0x80000000u || setpoint_q16 < RW_SPEED_LOOP_HOLD_MIN_Q16 ||
        !loop->estimator.state.primed) {
        return false;
    }
    return rw_mul_u32_u64(silence_us, (uint32_t)setpoint_q16) > loop->state.stale_bound_q16;
}

/*
 * Discrete law (speed step k, dt = dt_s), in Q16.16 m/s and throttle fractions:
 *   r[k]  = ramp(target', dt)           target' = 0 (LAND), the airborne approach (AIRBORNE), else target
 *   LAND and r[k] <= 0:                 PI at rest, pulse = ESC minimum
 *   stale encoder (see encoder_stale):  pulse and PI held
 *   ff[k] = throttle_map(r[k], V)       the no-load throttle for the setpoint at battery V
 *   lo    = throttle_map(guard, V)      AIRBORNE (else 0): the PI's lower limit
 *   u[k]  = PI(r[k], measured, ff[k], dt) within [lo, out_max]
 *   pulse = max(pulse_min_us, pulse(u[k]))
 */
uint16_t rw_speed_loop_step(rw_speed_loop *loop, rw_speed_loop_mode mode, float target_mps, uint32_t now_us,
                            float dt_s)
{
    if (mode == RW_SPEED_LOOP_OFF) {
        rw_speed_loop_reset(loop);
        return loop->state.pulse_us;
    }
    const uint16_t esc_min = loop->throttle.cfg.pulse_min_us;
    int32_t target_q16 = mode == RW_SPEED_LOOP_LAND ? 0 : rw_f32_to_q16(target_mps);
    if (mode == RW_SPEED_LOOP_AIRBORNE) {
        target_q16 = airborne_target_q16(loop, target_q16, dt_s);
    }
    const int32_t setpoint_q16 = rw_ramp_step(&loop->ramp, target_q16, dt_s);
    loop->state.setpoint_q16 = setpoint_q16;
    if (mode == RW_SPEED_LOOP_LAND && setpoint_q16 <= 0) {
        rw_pi_controller_reset(&loop->pi);
        loop->state.pulse_us = esc_min;
        loop->state.pulse_third_us = (uint16_t)(3u * esc_min);
        return esc_min;
    }
    if (encoder_stale(loop, setpoint_q16, now_us)) {
        return loop->state.pulse_us; /* pulse and PI state unchanged */
    }
    const float battery_v = loop->state.battery_v;
    const int32_t ff_q16 = rw_throttle_map_feed_forward(&loop->throttle, setpoint_q16, battery_v);
    rw_pi_controller_set_out_min_q16(
        &loop->pi,
        mode == RW_SPEED_LOOP_AIRBORNE ? rw_throttle_map_feed_forward(&loop->throttle, loop->state.guard_q16, battery_v) : 0);
    const int32_t u_q16 = rw_pi_controller_step(&loop->pi, setpoint_q16,
                                                rw_mt_speed_estimator_rope_mps_q16(&loop->estimator), ff_q16, dt_s);
    /* at the timer's resolution (1/3 us); its whole microseconds are what rw_throttle_map_pulse_us gives */
    uint16_t pulse_third = rw_throttle_map_pulse_third_us(&loop->throttle, u_q16);
    uint16_t pulse = rw_throttle_map_third_us_to_us(pulse_third);
    if (pulse < esc_min) {
        pulse = esc_min;
        pulse_third = (uint16_t)(3u * esc_min);
    }
    loop->state.pulse_us = pulse;
    loop->state.pulse_third_us = pulse_third;
    return pulse;
}

uint16_t rw_speed_loop_pulse_us(const rw_speed_loop *loop)
{
    return loop->state.pulse_us;
}

uint16_t rw_speed_loop_pulse_third_us(const rw_speed_loop *loop)
{
    return loop->state.pulse_third_us;
}

float rw_speed_loop_setpoint_mps(const rw_speed_loop *loop)
{
    return rw_f32_from_q16(loop->state.setpoint_q16);
}

int32_t rw_speed_loop_measured_q16(const rw_speed_loop *loop)
{
    return rw_mt_speed_estimator_rope_mps_q16(&loop->estimator);
}

float rw_speed_loop_battery_v(const rw_speed_loop *loop)
{
    return loop->state.battery_v;
}
