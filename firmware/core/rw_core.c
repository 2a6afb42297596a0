#include "rw_core.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "rw_core_internal.h"
#include "rw_float_bits.h"

/* A tick longer than this (a debugger pause, a stalled loop) is integrated as this long, so the PI and
 * ramp never take one giant step; the uptime still advances by the real time. */
#define RW_CORE_MAX_CONTROL_DT_S 0.05f

/* The encoder-hold threshold of control() is never under this many microseconds (3000.0f there). */
#define RW_CORE_ENCODER_STALE_MIN_US 3000u
/* 1 / RW_CORE_GUARD_APPROACH_S and RW_CORE_GUARD_APPROACH_MIN_MPS2 in Q16.16 */
#define RW_CORE_GUARD_APPROACH_PER_S_Q16 ((int32_t)(65536.0f / RW_CORE_GUARD_APPROACH_S))
#define RW_CORE_GUARD_APPROACH_MIN_Q16 ((int32_t)(RW_CORE_GUARD_APPROACH_MIN_MPS2 * 65536.0f))
/* RW_CORE_ENCODER_HOLD_MIN_MPS in Q16.16 */
#define RW_CORE_ENCODER_HOLD_MIN_Q16 ((int32_t)(RW_CORE_ENCODER_HOLD_MIN_MPS * 65536.0f))

/* x k rounded half up and saturated to 0..65535 (NaN and x <= 0 -> 0) for k = k_odd 2^k_shift (1000 =
 * 125 2^3, 60 = 15 2^2): the same product, rounded as the float multiply rounds it (rw_f32_mul_small), with
 * no soft-float call (__aeabi_fmul is ~120 instructions on the M0+). */
static uint16_t sat_u16_times(float x, uint32_t k_odd, int32_t k_shift)
{
    if (!rw_f32_positive(x)) {
        return 0u;
    }
    if (!rw_f32_finite(x)) {
        return 65535u;
    }
    int32_t exp2;
    const uint32_t p = rw_f32_mul_small(x, k_odd, k_shift, &exp2); /* x k = p 2^exp2, p <= 2^24 */
    if (exp2 >= 0) {
        return 65535u; /* >= 2^23 */
    }
    const uint32_t shift = (uint32_t)-exp2;
    if (shift >= 26u) {
        return 0u; /* < 0.5 */
    }
    const uint32_t rounded = (p + (1u << (shift - 1u))) >> shift;
    return rounded >= 65535u ? 65535u : (uint16_t)rounded;
}

/* (int32_t)(x k) for k = k_odd 2^k_shift: the float product truncated towards zero, without soft-float
 * calls; NaN gives 0, values beyond the int32 range saturate. */
static int32_t trunc_i32_times(float x, uint32_t k_odd, int32_t k_shift)
{
    if (rw_f32_isnan(x)) {
        return 0;
    }
    const bool negative = (rw_f32_bits(x) & 0x80000000u) != 0u;
    uint32_t magnitude = 0x80000000u; /* saturated */
    if (rw_f32_finite(x)) {
        int32_t exp2;
        const uint32_t p = rw_f32_mul_small(x, k_odd, k_shift, &exp2);
        if (exp2 < 0) {
            magnitude = (uint32_t)-exp2 >= 32u ? 0u : p >> (uint32_t)-exp2;
        } else if (exp2 <= 7) {
            magnitude = p << (uint32_t)exp2; /* <= 2^31 */
        }
    }
    if (negative) {
        return magnitude >= 0x80000000u ? INT32_MIN : -(int32_t)magnitude;
    }
    return magnitude >= 0x80000000u ? INT32_MAX : (int32_t)magnitude;
}

/* (float)dt_us 1e-6, capped at RW_CORE_MAX_CONTROL_DT_S: the same value, kept for the dt_us it was
 * computed for (the tick period repeats, a conversion and a multiply are ~100 instructions each). */
static float capped_dt_s(uint32_t dt_us, uint32_t *memo_us, float *memo_s)
{
    if (dt_us != *memo_us) {
        float dt_s = (float)dt_us * 1.0e-6f;
        if (dt_s > RW_CORE_MAX_CONTROL_DT_S) {
            dt_s = RW_CORE_MAX_CONTROL_DT_S;
        }
        *memo_us = dt_us;
        *memo_s = dt_s;
    }
    return *memo_s;
}

/* Push the current parameter values into the controllers' public configs. */
void rw_core_apply_params(rw_core *core)
{
    const rw_params *p = &core->params;
    rw_mt_speed_estimator_config est = {
        .counts_per_rev = (uint32_t)rw_params_get(p, RW_PARAM_ENCODER_COUNTS_PER_REV),
        .timeout_us = (uint32_t)(rw_params_get(p, RW_PARAM_ENCODER_TIMEOUT_S) * 1.0e6f),
        .wheel_radius_m = rw_params_get(p, RW_PARAM_WHEEL_RADIUS_M),
        .filter_tau_s = rw_params_get(p, RW_PARAM_SPEED_FILTER_TAU_S),
    };
    core->state.speed.cfg = est;
    core->state.pi.cfg.kp = rw_params_get(p, RW_PARAM_SPEED_KP);
    core->state.pi.cfg.ki_per_s = rw_params_get(p, RW_PARAM_SPEED_KI);
    core->state.pi.cfg.out_min = 0.0f;
    core->state.pi.cfg.out_max = 1.0f;
    core->state.ramp.cfg.rate_up_per_s = rw_params_get(p, RW_PARAM_RAMP_UP_MPS2);
    core->state.ramp.cfg.rate_down_per_s = rw_params_get(p, RW_PARAM_RAMP_DOWN_MPS2);
    core->state.throttle.cfg.kv_rpm_per_v = rw_params_get(p, RW_PARAM_MOTOR_KV_RPM_PER_V);
    core->state.throttle.cfg.wheel_radius_m = rw_params_get(p, RW_PARAM_WHEEL_RADIUS_M);
    core->state.throttle.cfg.pulse_min_us = (uint16_t)rw_params_get(p, RW_PARAM_ESC_MIN_US);
    core->state.throttle.cfg.pulse_max_us = 2000u;
    core->state.guard.cfg.tov_mps = rw_params_get(p, RW_PARAM_TOV_MPS);
    core->state.guard.cfg.margin = rw_params_get(p, RW_PARAM_TOV_MARGIN);
    core->state.guard.cfg.collapse_time_s = rw_params_get(p, RW_PARAM_COLLAPSE_TIME_S);
    rw_spindle_config *sp = &core->state.spindle.cfg;
    sp->lead_mm_per_rev = rw_params_get(p, RW_PARAM_LEAD_MM_PER_REV);
    sp->guide_min_mm = rw_params_get(p, RW_PARAM_GUIDE_MIN_MM);
    sp->guide_max_mm = rw_params_get(p, RW_PARAM_GUIDE_MAX_MM);
    sp->kp_per_s = rw_params_get(p, RW_PARAM_SPINDLE_KP_PER_S);
    sp->max_speed_mmps = rw_params_get(p, RW_PARAM_SPINDLE_MAX_SPEED_MMPS);
    sp->tolerance_mm = rw_params_get(p, RW_PARAM_SPINDLE_TOLERANCE_MM);
    sp->homing_speed_mmps = rw_params_get(p, RW_PARAM_HOMING_SPEED_MMPS);
    sp->homing_load_pct = rw_params_get(p, RW_PARAM_HOMING_LOAD_PCT);
    sp->stall_load_pct = rw_params_get(p, RW_PARAM_SPINDLE_STALL_LOAD_PCT);
    sp->stall_time_s = rw_params_get(p, RW_PARAM_SPINDLE_STALL_TIME_S);
    sp->secure_load_pct = rw_params_get(p, RW_PARAM_GRASP_SECURE_LOAD_PCT);
    sp->retract_speed_mmps = rw_params_get(p, RW_PARAM_RETRACT_SPEED_MMPS);
    sp->timeout_s = rw_params_get(p, RW_PARAM_SPINDLE_TIMEOUT_S);
    rw_core_load_loss_apply_params(core);
}

void rw_core_init(rw_core *core)
{
    memset(core, 0, sizeof *core);
    rw_params_init_defaults(&core->params);
    rw_mt_speed_estimator_config est;
    rw_mt_speed_estimator_config_defaults(&est);
    rw_mt_speed_estimator_init(&core->state.speed, &est);
    rw_pi_controller_config pi;
    rw_pi_controller_config_defaults(&pi);
    rw_pi_controller_init(&core->state.pi, &pi);
    rw_ramp_config ramp;
    rw_ramp_config_defaults(&ramp);
    rw_ramp_init(&core->state.ramp, &ramp);
    rw_throttle_map_config thr;
    rw_throttle_map_config_defaults(&thr);
    rw_throttle_map_init(&core->state.throttle, &thr);
    rw_tov_guard_config guard;
    rw_tov_guard_config_defaults(&guard);
    rw_tov_guard_init(&core->state.guard, &guard);
    rw_duplicate_cache_reset(&core->state.duplicates);
    rw_outbox_reset(&core->state.outbox);
    rw_signer_reset(&core->state.signer);
    rw_spindle_config spindle = { 0 };
    rw_spindle_init(&core->state.spindle, &spindle);
    rw_load_monitor_config load_monitor;
    rw_load_monitor_config_defaults(&load_monitor);
    rw_load_monitor_init(&core->state.load_monitor, &load_monitor);
    rw_core_apply_params(core);
    core->state.state = RW_STATE_DISARMED;
    core->state.peer_link = RW_LINK_WIFI; /* until a host is heard, the WiFi HAL drops what has no peer */
    core->state.pulse_us = (uint16_t)rw_params_get(&core->params, RW_PARAM_ESC_MIN_US);
    core->state.pulse_third_us = (uint16_t)(3u * core->state.pulse_us);
    rw_burst_reset(&core->state.burst);
}

/* Bindings hand rw_config_set_params the core's address for its parameter values. */
_Static_assert(offsetof(rw_core, params) == 0, "rw_core.params must stay the first member");

bool rw_core_tx_idle(const rw_core *core)
{
    return rw_outbox_peek(&core->state.outbox) == NULL && !rw_signer_busy(&core->state.signer);
}

size_t rw_core_sizeof(void)
{
    return sizeof(rw_core);
}

int rw_core_set_param(rw_core *core, uint8_t param_id, float value)
{
    int result = rw_params_set(&core->params, param_id, value, core->state.state == RW_STATE_DISARMED);
    if (result == RW_DECODE_OK) {
        rw_core_apply_params(core);
        if (param_id == RW_PARAM_TELEMETRY_RATE_HZ) {
            core->state.telemetry_due_ms = core->state.uptime_ms; /* the new period starts now */
        }
    }
    return result;
}

void rw_core_emit_event(rw_core *core, uint8_t event, uint8_t from, uint8_t to, int32_t arg)
{
    rw_msg_event msg = {
        .time_ms = core->state.uptime_ms,
        .event_seq = ++core->state.counters.events,
        .event = event,
        .state_from = from,
        .state_to = to,
        .arg = arg,
    };
    uint8_t frame[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_event_encode(&msg, 0u, frame, sizeof frame); /* numbered when it leaves */
    rw_outbox_push(&core->state.outbox, RW_OUTBOX_EVENT, frame, len);
}

void rw_core_set_state(rw_core *core, uint8_t new_state, uint8_t cause)
{
    uint8_t old = core->state.state;
    if (old == new_state) {
        return;
    }
    core->state.state = new_state;
    if (new_state == RW_STATE_SPINUP && (old == RW_STATE_ARMED)) {
        rw_pi_controller_reset(&core->state.pi);
        rw_ramp_reset_to(&core->state.ramp, core->state.measured_mps);
    }
    if (new_state == RW_STATE_SPINDOWN) {
        core->state.spindown_cause = cause;
    }
    if (new_state == RW_STATE_AIRBORNE) {
        rw_tov_guard_reset(&core->state.guard);
    }
    rw_core_emit_event(core, RW_EVENT_KIND_STATE_CHANGED, old, new_state, (int32_t)cause);
}

void rw_core_raise_fault(rw_core *core, uint16_t fault_bit)
{
    if ((core->state.fault_bits & fault_bit) == 0u) {
        core->state.fault_bits |= fault_bit;
        rw_core_emit_event(core, RW_EVENT_KIND_FAULT_RAISED, core->state.state, core->state.state, (int32_t)fault_bit);
    }
    /* Only a blind speed loop makes the rope unsafe: FAULT holds the ESC at its minimum. The other faults
     * (battery, spindle) are handled where they are detected and leave the state machine alone. */
    if (fault_bit == RW_FAULT_ENCODER_SILENT && core->state.state != RW_STATE_ESTOP) {
        rw_spindle_stop(&core->state.spindle);
        core->state.grasp_pending = false;
        rw_core_set_state(core, RW_STATE_FAULT, RW_CAUSE_FAULT);
    }
}

static bool rope_driven(uint8_t state)
{
    return state == RW_STATE_SPINUP || state == RW_STATE_AIRBORNE || state == RW_STATE_SPINDOWN ||
           state == RW_STATE_RELAX;
}

/* States whose rope setpoint ramps to zero (a commanded or forced landing). */
static bool rope_landing(uint8_t state)
{
    return state == RW_STATE_SPINDOWN || state == RW_STATE_RELAX;
}

static void supervise(rw_core *core, float dt_s, uint32_t dt_ms, uint32_t encoder_counts_delta)
{
    const rw_params *p = &core->params;
    uint8_t st = core->state.state;

    /* the time thresholds are compared as (float)elapsed_ms >= threshold_s * 1000.0f, on the bit patterns */
    if (!core->state.arming_hold_done &&
        rw_f32_ms_past(core->state.uptime_ms, rw_params_get(p, RW_PARAM_ARM_HOLD_S), true)) {
        core->state.arming_hold_done = true;
        rw_core_emit_event(core, RW_EVENT_KIND_ARMING_HOLD_DONE, st, st, 0);
    }

    /* Heartbeat: the host must be heard from within heartbeat_timeout_s while the rope is driven. */
    uint32_t silence_ms = core->state.uptime_ms - core->state.last_host_frame_ms;
    if (rw_f32_ms_past(silence_ms, rw_params_get(p, RW_PARAM_HEARTBEAT_TIMEOUT_S), false)) {
        if (!core->state.heartbeat_lost && st != RW_STATE_DISARMED) {
            core->state.heartbeat_lost = true;
            rw_core_emit_event(core, RW_EVENT_KIND_HEARTBEAT_LOST, st, st, (int32_t)silence_ms);
            rw_spindle_stop(&core->state.spindle); /* no guide move (loop size, homing) goes on without a host */
        }
        if (st == RW_STATE_SPINUP || st == RW_STATE_AIRBORNE) {
            core->state.target_mps = 0.0f;
            rw_core_set_state(core, RW_STATE_SPINDOWN, RW_CAUSE_HEARTBEAT_LOST);
        } else if (st == RW_STATE_RETRACT) {
            rw_spindle_stop(&core->state.spindle);
            rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_HEARTBEAT_LOST);
        } else if (st == RW_STATE_RELAX) {
            core->state.grasp_pending = false; /* land, but do not go on to retract without a host */
        }
    }

    /* Battery: under the cutoff for battery_cutoff_time_s (brief load sags pass) -> land the rope. */
    if (rw_f32_lt(core->state.battery_v, rw_params_get(p, RW_PARAM_BATTERY_CUTOFF_V))) {
        core->state.battery_low_ms += dt_ms;
        if (rw_f32_ms_past(core->state.battery_low_ms, rw_params_get(p, RW_PARAM_BATTERY_CUTOFF_TIME_S), true)) {
            rw_core_raise_fault(core, RW_FAULT_BATTERY_LOW);
            st = core->state.state;
            if (st == RW_STATE_SPINUP || st == RW_STATE_AIRBORNE) {
                core->state.target_mps = 0.0f;
                rw_core_set_state(core, RW_STATE_SPINDOWN, RW_CAUSE_BATTERY_LOW);
            }
        }
    } else {
        core->state.battery_low_ms = 0u;
    }

    /* Encoder silent while the throttle is up: the speed loop is blind, stop driving. */
    uint16_t esc_min = core->state.throttle.cfg.pulse_min_us; /* (uint16_t)esc_min_us (rw_core_apply_params) */
    if (encoder_counts_delta == 0u && core->state.pulse_us > esc_min + RW_CORE_THROTTLE_ACTIVE_US) {
        core->state.encoder_silent_ms += dt_ms;
        if (rw_f32_ms_past(core->state.encoder_silent_ms, rw_params_get(p, RW_PARAM_ENCODER_TIMEOUT_S), false)) {
            rw_core_raise_fault(core, RW_FAULT_ENCODER_SILENT);
        }
    } else {
        core->state.encoder_silent_ms = 0u;
    }

    st = core->state.state;
    float guard_mps = rw_tov_guard_min_airborne_mps(&core->state.guard);
    if (st == RW_STATE_AIRBORNE) {
        if (rw_tov_guard_step(&core->state.guard, core->state.measured_mps, dt_s)) {
            rw_core_emit_event(core, RW_EVENT_KIND_LOOP_COLLAPSED, st, st,
                               (int32_t)sat_u16_times(core->state.measured_mps, 125u, 3)); /* x 1000 */
            rw_core_set_state(core, RW_STATE_SPINUP, RW_CAUSE_LOOP_COLLAPSED);
        }
    } else if (st == RW_STATE_SPINUP && rw_f32_ge(core->state.target_mps, guard_mps) &&
               rw_f32_ge(core->state.measured_mps, guard_mps)) {
        rw_core_set_state(core, RW_STATE_AIRBORNE, RW_CAUSE_SPEED_REACHED);
    } else if (st == RW_STATE_SPINDOWN && rw_f32_le(rw_ramp_output(&core->state.ramp), 0.0f) &&
               rw_f32_lt(core->state.measured_mps, RW_CORE_STOPPED_MPS)) {
        rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_SPEED_REACHED);
    } else if (st == RW_STATE_RELAX && core->state.grasp_pending && rw_f32_le(rw_ramp_output(&core->state.ramp), 0.0f) &&
               rw_f32_lt(core->state.measured_mps, RW_CORE_STOPPED_MPS)) {
        core->state.grasp_pending = false;
        rw_spindle_retract(&core->state.spindle);
        rw_core_set_state(core, RW_STATE_RETRACT, RW_CAUSE_SPEED_REACHED);
    }
}

/* The spindle loop, every RW_CORE_SPINDLE_PERIOD_MS: read the servo, step, write, act on the outcome.
 * elapsed_ms: the real time since the previous step (the period, or more after a gap). */
static void spindle_tick(rw_core *core, const rw_hal *hal, uint32_t elapsed_ms)
{
    if (hal->spindle == NULL) {
        return;
    }
    rw_spindle_reading reading;
    bool answered = hal->spindle->read(hal->spindle->ctx, &reading);
    rw_spindle *sp = &core->state.spindle;
    uint8_t st = core->state.state;
    switch (rw_spindle_step(sp, answered ? &reading : NULL, elapsed_ms)) {
    case RW_SPINDLE_HOMED_BY_STALL:
        rw_core_emit_event(core, RW_EVENT_KIND_SPINDLE_HOMED, st, st, 1);
        break;
    case RW_SPINDLE_HOMED_BY_SWITCH:
        rw_core_emit_event(core, RW_EVENT_KIND_SPINDLE_HOMED, st, st, 2);
        break;
    case RW_SPINDLE_TARGET_REACHED:
        rw_core_emit_event(core, RW_EVENT_KIND_SPINDLE_TARGET_REACHED, st, st,
                           sp->state.position_um);
        break;
    case RW_SPINDLE_SECURED:
        if (st == RW_STATE_RETRACT) {
            rw_core_set_state(core, RW_STATE_HOLD, RW_CAUSE_LOAD_SECURED);
        }
        break;
    case RW_SPINDLE_STROKE_END:
        if (st == RW_STATE_RETRACT) {
            rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_STROKE_END);
        }
        break;
    case RW_SPINDLE_STALLED:
        rw_core_raise_fault(core, RW_FAULT_SPINDLE_STALL);
        break;
    case RW_SPINDLE_NO_ANSWER:
        rw_core_raise_fault(core, RW_FAULT_SPINDLE_NO_ANSWER);
        if (st == RW_STATE_RETRACT) {
            rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_FAULT);
        }
        break;
    case RW_SPINDLE_NOTHING:
        break;
    }
    /* The spindle never moves while the device is disarmed, in ESTOP or in FAULT. */
    st = core->state.state;
    if (st == RW_STATE_ESTOP || st == RW_STATE_FAULT ||
        (st == RW_STATE_DISARMED && sp->state.mode != RW_SPINDLE_HOMING)) {
        rw_spindle_stop(sp);
        sp->state.moving_speed_raw = 0u;
    }
    hal->spindle->write_moving_speed_raw(hal->spindle->ctx, sp->state.moving_speed_raw);
}

/* The rope speed loop. Every tick: a state that does not drive the rope holds the ESC at its minimum at
 * once. Speed ticks only: ramp, feed-forward and PI with dt_s since the previous speed tick. */
static void control(rw_core *core, float dt_s, bool speed_tick)
{
    uint8_t st = core->state.state;
    uint16_t esc_min = core->state.throttle.cfg.pulse_min_us; /* (uint16_t)esc_min_us (rw_core_apply_params) */
    if (!rope_driven(st)) {
        rw_pi_controller_reset(&core->state.pi);
        rw_ramp_reset_to(&core->state.ramp, 0.0f);
        core->state.setpoint_mps = 0.0f;
        core->state.pulse_us = esc_min;
        return;
    }
    if (!speed_tick) {
        return;
    }
    /* Q16.16 m/s from here on (rw_float_bits.h): the ramp, the feed-forward and the PI run in integers */
    const int32_t target_q16 = rope_landing(st) ? 0 : rw_f32_to_q16(core->state.target_mps);
    /* While airborne the setpoint comes down onto the guard exponentially (time constant
     * RW_CORE_GUARD_APPROACH_S), not at the full ramp rate, so that the speed loop lands on it without
     * undershooting into the band under ToV x margin: the fall rate is min(ramp_down_mps2, room /
     * RW_CORE_GUARD_APPROACH_S + RW_CORE_GUARD_APPROACH_MIN_MPS2), room = setpoint - guard. In fixed point:
     * the approach step (rate x dt) bounds the target the ramp steps towards, and the ramp's own fall rate
     * bounds it further (the same min). A setpoint already under the guard (the guard raised in flight) falls
     * at the minimum approach rate. */
    core->state.ramp.cfg.rate_down_per_s = rw_params_get(&core->params, RW_PARAM_RAMP_DOWN_MPS2);
    int32_t bounded_target_q16 = target_q16;
    const int32_t ramp_q16 = rw_ramp_output_q16(&core->state.ramp);
    if (st == RW_STATE_AIRBORNE && target_q16 < ramp_q16) {
        const int64_t room_q16 = (int64_t)ramp_q16 - rw_tov_guard_min_airborne_mps_q16(&core->state.guard);
        const int32_t room_clamped_q16 = room_q16 > INT32_MAX / 4 ? INT32_MAX / 4 : (room_q16 < 0 ? 0 : (int32_t)room_q16);
        const int64_t approach_q16 =
            (rw_mul_s32_s64(room_clamped_q16, RW_CORE_GUARD_APPROACH_PER_S_Q16) >> 16) + RW_CORE_GUARD_APPROACH_MIN_Q16;
        const int64_t step_q16 = (rw_mul_s32_s64((int32_t)approach_q16, rw_f32_to_fixed(dt_s, 32u)) + 0x80000000) >> 32;
        if ((int64_t)ramp_q16 - step_q16 > target_q16) {
            bounded_target_q16 = (int32_t)(ramp_q16 - step_q16);
        }
    }
    const int32_t setpoint_q16 = rw_ramp_step(&core->state.ramp, bounded_target_q16, dt_s);
    core->state.setpoint_mps = rw_f32_from_q16(setpoint_q16);
    if (rope_landing(st) && setpoint_q16 <= 0) {
        rw_pi_controller_reset(&core->state.pi);
        core->state.pulse_us = esc_min;
        return;
    }
    /* A blind loop must not act: with the rope meant to run at >= 1 m/s, no encoder edge for four edge
     * periods at the setpoint (3 ms at least) means the reading is stale, not that the rope stopped: hold the
     * throttle and the integrator until edges come back (or encoder_timeout_s raises ENCODER_SILENT). */
    uint32_t silence_us = core->state.last_now_us - core->state.speed.state.last_edge_us;
    /* stale_us is at least RW_CORE_ENCODER_STALE_MIN_US: a shorter silence (every tick of a turning wheel)
     * needs no division */
    if (silence_us > RW_CORE_ENCODER_STALE_MIN_US && silence_us < 0x80000000u &&
        setpoint_q16 >= RW_CORE_ENCODER_HOLD_MIN_Q16 && core->state.speed.state.primed) {
        const rw_mt_speed_estimator_config *enc = &core->state.speed.cfg;
        const float setpoint = core->state.setpoint_mps;
        float edge_period_us = 6.2831853f * 1.0e6f * enc->wheel_radius_m / (setpoint * (float)enc->counts_per_rev);
        float stale_us = 4.0f * edge_period_us < 3000.0f ? 3000.0f : 4.0f * edge_period_us;
        if ((float)silence_us > stale_us) {
            return; /* pulse and PI state unchanged */
        }
    }
    const int32_t ff_q16 = rw_throttle_map_feed_forward(&core->state.throttle, setpoint_q16, core->state.ff_battery_v);
    /* ToV guard on the output too: while airborne the throttle never goes under what holds the guard speed
     * without load, so a step down to the guard cannot brake the rope through it (the PI's anti-windup
     * knows the floor). */
    core->state.pi.cfg.out_min =
        st == RW_STATE_AIRBORNE
            ? rw_f32_from_q16(rw_throttle_map_feed_forward(
                  &core->state.throttle, rw_tov_guard_min_airborne_mps_q16(&core->state.guard),
                  core->state.ff_battery_v))
            : 0.0f;
    /* measured_mps is this speed, as a float (the estimator step's return) */
    int32_t u_q16 = rw_pi_controller_step(&core->state.pi, setpoint_q16,
                                          rw_mt_speed_estimator_rope_mps_q16(&core->state.speed), ff_q16, dt_s);
    /* at the timer's resolution (1/3 us); its whole microseconds are what rw_throttle_map_pulse_us gives */
    uint16_t pulse_third = rw_throttle_map_pulse_third_us(&core->state.throttle, u_q16);
    uint16_t pulse = rw_throttle_map_third_us_to_us(pulse_third);
    if (pulse < esc_min) {
        pulse = esc_min;
        pulse_third = (uint16_t)(3u * esc_min);
    }
    core->state.pulse_us = pulse;
    core->state.pulse_third_us = pulse_third;
}

static uint8_t spindle_flags(const rw_spindle *sp)
{
    uint8_t flags = 0u;
    flags |= sp->state.homed ? RW_SPINDLE_FLAG_HOMED : 0u;
    flags |= sp->state.answering ? RW_SPINDLE_FLAG_ANSWERING : 0u;
    flags |= sp->state.turns.state.dead_reckoning ? RW_SPINDLE_FLAG_DEAD_ZONE : 0u;
    flags |= sp->state.moving_speed_raw != 0u ? RW_SPINDLE_FLAG_MOVING : 0u;
    flags |= sp->state.mode == RW_SPINDLE_HOMING ? RW_SPINDLE_FLAG_HOMING : 0u;
    return flags;
}

static const rw_hal_link *link_of(const rw_hal *hal, rw_link_id link)
{
    return link == RW_LINK_SERIAL ? hal->serial : (link == RW_LINK_WIFI ? hal->link : NULL);
}

uint16_t rw_core_take_seq(rw_core *core, rw_link_id link)
{
    return core->state.tx_seq[link == RW_LINK_SERIAL ? 1 : 0]++;
}

void rw_core_link_send(rw_core *core, const rw_hal *hal, rw_link_id link, bool reply, const uint8_t *frame, size_t len)
{
    const rw_hal_link *l = link_of(hal, link);
    if (l == NULL || len == 0u) {
        return;
    }
    if (link == RW_LINK_WIFI && core->state.config.key_set != 0u) {
        uint8_t signed_frame[RW_MAX_FRAME_LEN];
        memcpy(signed_frame, frame, len);
        len = rw_frame_sign(signed_frame, len, sizeof signed_frame, rw_core_session_id(core), ++core->state.tx_counter,
                            core->state.config.key);
        if (len == 0u) {
            return;
        }
        (reply ? l->reply : l->send)(l->ctx, signed_frame, len);
        return;
    }
    (reply ? l->reply : l->send)(l->ctx, frame, len);
}

/* First tick: the stored configuration (key, parameters) and a new session: the boot counter goes up and is
 * written back at once, so that no later boot can reuse this session id (session epoch + boot counter,
 * rw_config.h). With the counter used up the key is forgotten rather than an id reused. */
static void load_config(rw_core *core, const rw_hal *hal)
{
    rw_config *c = &core->state.config;
    bool stored = hal->config != NULL && hal->config->load(hal->config->ctx, c, sizeof *c) && rw_config_valid(c);
    if (stored) {
        for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
            if (rw_params_check(&core->params, (uint8_t)i, c->params[i], true) == RW_DECODE_OK) {
                core->params.value[i] = c->params[i];
            }
        }
        rw_core_apply_params(core);
    } else {
        rw_config_defaults(c);
        rw_config_set_params(c, core->params.value);
    }
    if (!rw_config_next_boot(c)) {
        rw_config_clear_key(c);
    }
    core->state.session_id = rw_config_session_id(c);
    if (hal->config != NULL) {
        (void)hal->config->save(hal->config->ctx, c, sizeof *c);
    }
}

static void queue_telemetry(rw_core *core, const rw_hal *hal)
{
    const rw_core_counters *c = &core->state.counters;
    uint32_t age_ms = core->state.uptime_ms - core->state.last_host_frame_ms;
    rw_msg_telemetry msg = {
        .time_ms = core->state.uptime_ms,
        .state = core->state.state,
        .fault_bits = core->state.fault_bits,
        .rope_speed_target_mmps = sat_u16_times(core->state.target_mps, 125u, 3), /* x 1000 */
        .rope_speed_setpoint_mmps = sat_u16_times(core->state.setpoint_mps, 125u, 3),
        .rope_speed_mmps = sat_u16_times(core->state.measured_mps, 125u, 3),
        .motor_rpm = sat_u16_times(rw_mt_speed_estimator_rev_per_s(&core->state.speed), 15u, 2), /* x 60 */
        .esc_pulse_us = core->state.pulse_us,
        .battery_mv = core->state.battery_mv,
        .heartbeat_age_ms = age_ms > 65535u ? 65535u : (uint16_t)age_ms,
        .rx_ok = c->rx_ok,
        .rx_bad = c->rx_bad,
        .rx_duplicates = c->rx_duplicates,
        .nacks = c->nacks,
        .events = c->events,
        .tick_overruns = hal->scheduler != NULL ? (uint16_t)hal->scheduler->tick_overruns(hal->scheduler->ctx) : 0u,
        .guide_position_um = trunc_i32_times(core->state.spindle.state.position_mm, 125u, 3), /* x 1000 */
        .guide_target_um = trunc_i32_times(core->state.spindle.state.target_mm, 125u, 3),
        .spindle_load_permille = core->state.spindle.state.load_permille,
        .spindle_flags = spindle_flags(&core->state.spindle),
        .spindle_rejected = core->state.spindle.state.turns.state.rejected,
        .rx_auth_failed = c->rx_auth_failed,
        .rx_replayed = c->rx_replayed,
        .tx_dropped = rw_outbox_dropped(&core->state.outbox),
        .esc_pulse_third_us = core->state.pulse_third_us,
        .spindle_moving_speed_raw = core->state.spindle.state.moving_speed_raw,
        .encoder_counts = core->state.encoder_counts,
        .encoder_edge_us = core->state.encoder_edge_us,
    };
    /* encoded straight into its outbox slot (no copy); a full outbox drops it (counted), as a push would */
    rw_outbox_slot *slot = rw_outbox_reserve(&core->state.outbox, RW_OUTBOX_TELEMETRY);
    if (slot != NULL) {
        size_t len = rw_msg_telemetry_encode(&msg, 0u, slot->bytes, sizeof slot->bytes); /* numbered when it leaves */
        rw_outbox_commit(&core->state.outbox, slot, RW_OUTBOX_TELEMETRY, len);
    }
}

/* The next BURST_DATA frame into the outbox when it is empty and nothing is being signed; true if packed. */
static bool queue_burst_frame(rw_core *core)
{
    if (rw_signer_busy(&core->state.signer) || rw_outbox_peek(&core->state.outbox) != NULL) {
        return false;
    }
    rw_msg_burst_data msg;
    rw_burst_next_frame(&core->state.burst, &msg);
    rw_outbox_slot *slot = rw_outbox_reserve(&core->state.outbox, RW_OUTBOX_BURST);
    if (slot != NULL) {
        size_t len = rw_msg_burst_data_encode(&msg, 0u, slot->bytes, sizeof slot->bytes); /* numbered when it leaves */
        rw_outbox_commit(&core->state.outbox, slot, RW_OUTBOX_BURST, len);
    }
    return true;
}

/* round(1000 / telemetry_rate_hz) ms, computed once per rate (a float division is ~350 instructions). */
static uint32_t telemetry_period_ms(rw_core *core)
{
    float rate_hz = rw_params_get(&core->params, RW_PARAM_TELEMETRY_RATE_HZ);
    if (!rw_f32_same(rate_hz, core->state.telemetry_rate_hz_memo)) {
        core->state.telemetry_period_ms = (uint32_t)(1000.0f / rate_hz + 0.5f);
        core->state.telemetry_rate_hz_memo = rate_hz;
    }
    return core->state.telemetry_period_ms;
}

/* Step 5's send: the next outbox frame goes to the peer, at most one datagram a tick (none when this tick
 * already answered a command). Over a keyed WiFi link it is signed first, on idle ticks only and in steps
 * (rw_signer.h), each idle tick doing at most RW_CORE_MAC_TICK_BUDGET blocks' worth of work: begin (copy,
 * checksum: RW_CORE_MAC_BEGIN_COST), absorb (one per block), finish and send (RW_CORE_MAC_FINISH_COST). So no
 * tick carries a whole MAC, and a telemetry frame leaves within two idle ticks. Its counter is taken when it
 * leaves. A frame the signer refuses (not a well-formed frame) is dropped and counted (tx_dropped). */
static void send_queued(rw_core *core, const rw_hal *hal, bool sent, bool idle_tick)
{
    rw_signer *signer = &core->state.signer;
    if (!rw_signer_busy(signer)) {
        const rw_outbox_slot *slot = sent ? NULL : rw_outbox_peek(&core->state.outbox);
        if (slot == NULL) {
            return;
        }
        if (core->state.peer_link != RW_LINK_WIFI || core->state.config.key_set == 0u) {
            uint8_t frame[RW_MAX_FRAME_LEN];
            memcpy(frame, slot->bytes, slot->len);
            size_t len = rw_frame_renumber(frame, slot->len, rw_core_take_seq(core, (rw_link_id)core->state.peer_link));
            rw_core_link_send(core, hal, (rw_link_id)core->state.peer_link, false, frame, len);
            rw_outbox_pop(&core->state.outbox, slot);
            return;
        }
        if (!idle_tick) {
            return;
        }
        if (!rw_signer_begin(signer, slot->bytes, slot->len, rw_core_take_seq(core, RW_LINK_WIFI),
                             rw_core_session_id(core), core->state.config.key)) {
            rw_outbox_count_drop(&core->state.outbox); /* counted: its seq is spent */
        }
        rw_outbox_pop(&core->state.outbox, slot);
        (void)rw_signer_absorb(signer, RW_CORE_MAC_TICK_BUDGET - RW_CORE_MAC_BEGIN_COST);
        return;
    }
    if (!idle_tick) {
        return;
    }
    const size_t now = rw_signer_absorb(signer, RW_CORE_MAC_TICK_BUDGET);
    if (rw_signer_blocks_left(signer) == 0u && now + RW_CORE_MAC_FINISH_COST <= RW_CORE_MAC_TICK_BUDGET && !sent &&
        hal->link != NULL) {
        const uint8_t *frame = NULL;
        size_t len = rw_signer_finish(signer, ++core->state.tx_counter, &frame);
        hal->link->send(hal->link->ctx, frame, len);
    }
}

void rw_core_tick(rw_core *core, const rw_hal *hal, uint32_t now_us)
{
    if (!core->state.started) {
        core->state.started = true;
        core->state.last_now_us = now_us;
        load_config(core, hal);
        rw_core_emit_event(core, RW_EVENT_KIND_BOOT, core->state.state, core->state.state, (int32_t)core->reset_cause);
    }
    uint32_t dt_us = now_us - core->state.last_now_us;
    core->state.last_now_us = now_us;
    uint32_t total_us = core->state.uptime_rem_us + dt_us;
    uint32_t dt_ms;
    if (total_us < 2000u && total_us >= dt_us) { /* the usual tick: no division (same result) */
        dt_ms = total_us >= 1000u ? 1u : 0u;
        total_us -= dt_ms * 1000u;
    } else {
        dt_ms = total_us / 1000u;
        total_us %= 1000u;
    }
    core->state.uptime_ms += dt_ms;
    core->state.uptime_rem_us = total_us;
    float dt_s = capped_dt_s(dt_us, &core->state.tick_dt_us_memo, &core->state.tick_dt_s_memo);
    /* the schedule (rw_core.h): speed ticks and other ticks alternate */
    const bool speed_tick = core->state.speed_tick_next;
    core->state.speed_tick_next = !speed_tick;
    uint32_t speed_dt_us = core->state.speed_dt_us + dt_us;
    core->state.speed_dt_us = speed_dt_us < dt_us ? UINT32_MAX : speed_dt_us; /* saturates */

    /* 1. sensors: the encoder every tick (supervision watches its count), the estimator on speed ticks */
    rw_encoder_sample enc = hal->encoder->read(hal->encoder->ctx);
    /* for TELEMETRY and bursts: edges since boot and the latest edge's time on the uptime clock (us), so what
     * the host sees does not depend on where the HAL's counters and tick clock started */
    if (!core->state.encoder_origin_set) {
        core->state.encoder_origin_set = true;
        core->state.encoder_boot_counts = enc.counts;
    }
    const uint32_t uptime_us = core->state.uptime_ms * 1000u + core->state.uptime_rem_us;
    core->state.encoder_counts = enc.counts - core->state.encoder_boot_counts;
    core->state.encoder_edge_us = uptime_us - (now_us - enc.last_edge_us);
    uint32_t counts_delta = enc.counts - core->state.speed.state.last_count;
    bool primed = core->state.speed.state.primed;
    float speed_dt_s = 0.0f;
    if (speed_tick) {
        speed_dt_s = capped_dt_s(core->state.speed_dt_us, &core->state.speed_dt_us_memo, &core->state.speed_dt_s_memo);
        core->state.speed_dt_us = 0u;
        /* the step returns rw_mt_speed_estimator_rope_mps (0 with an invalid config, which the parameter
         * ranges exclude) */
        core->state.measured_mps =
            rw_mt_speed_estimator_step(&core->state.speed, enc.counts, enc.last_edge_us, now_us, speed_dt_s);
    }
    uint16_t battery_mv = hal->battery->read_mv(hal->battery->ctx);
    if (battery_mv != core->state.battery_mv) { /* volts only when the reading changes */
        core->state.battery_mv = battery_mv;
        core->state.battery_v = (float)battery_mv * 1.0e-3f;
    }

    /* 2. at most one received datagram per link (USB serial first: it is where provisioning happens) */
    bool sent = hal->serial != NULL && rw_core_handle_datagram(core, hal, RW_LINK_SERIAL);
    sent = rw_core_handle_datagram(core, hal, RW_LINK_WIFI) || sent;

    /* 3. supervision, 4. control; the spindle and the telemetry pack only on other ticks, one job a tick */
    supervise(core, dt_s, dt_ms, primed ? counts_delta : 1u);
    const bool telemetry_due = (int32_t)(core->state.uptime_ms - core->state.telemetry_due_ms) >= 0;
    const bool spindle_due = (int32_t)(core->state.uptime_ms - core->state.spindle_due_ms) >= 0;
    if (!speed_tick && !telemetry_due && !spindle_due && !rw_f32_same(core->state.battery_v, core->state.ff_battery_v)) {
        /* an idle tick: the feed-forward's battery division happens here, not on a speed tick */
        core->state.ff_battery_v = core->state.battery_v;
        rw_throttle_map_prepare_battery(&core->state.throttle, core->state.ff_battery_v);
    }
    const bool spindle_ran = !speed_tick && !telemetry_due && spindle_due;
    if (spindle_ran) {
        /* the real time since the last spindle step: after a tick gap the dead reckoning must cover it */
        uint32_t elapsed_ms = core->state.uptime_ms - core->state.spindle_last_ms;
        if (elapsed_ms == 0u || elapsed_ms > 60000u) {
            elapsed_ms = RW_CORE_SPINDLE_PERIOD_MS; /* first step */
        }
        spindle_tick(core, hal, elapsed_ms);
        /* the load-loss check shares the 10 ms slot (its time constants are 50 ms and more; it reads the PI's
         * integral, which the speed ticks keep current). Its dt is the slot's period: the slot keeps it but
         * when a telemetry tick holds it back once (2 ms), and a constant dt keeps the filters' coefficients
         * (a float division each) computed once. */
        rw_core_load_loss_step(core);
        core->state.spindle_last_ms = core->state.uptime_ms;
        core->state.spindle_due_ms = core->state.uptime_ms + RW_CORE_SPINDLE_PERIOD_MS;
    }
    control(core, speed_dt_s, speed_tick);
    /* a state that stops the rope set only the whole-microsecond minimum: its thirds follow */
    if (rw_throttle_map_third_us_to_us(core->state.pulse_third_us) != core->state.pulse_us) {
        core->state.pulse_third_us = (uint16_t)(3u * core->state.pulse_us);
    }
    if (hal->esc->write_pulse_third_us != NULL) {
        hal->esc->write_pulse_third_us(hal->esc->ctx, core->state.pulse_third_us);
    } else { /* whole microseconds only: that is the pulse the ESCs get */
        core->state.pulse_third_us = (uint16_t)(3u * core->state.pulse_us);
        hal->esc->write_pulse_us(hal->esc->ctx, core->state.pulse_us);
    }
    if (rw_burst_capturing(&core->state.burst)) {
        const rw_burst_sample sample = { .encoder_counts = (uint16_t)core->state.encoder_counts,
                                         .encoder_edge_us = (uint16_t)core->state.encoder_edge_us,
                                         .esc_pulse_third_us = core->state.pulse_third_us,
                                         .battery_mv = battery_mv };
        rw_burst_record(&core->state.burst, core->state.uptime_ms, uptime_us, dt_us, &sample);
    }

    /* 5. telemetry, then at most one datagram out per tick */
    const bool telemetry_tick = !speed_tick && telemetry_due;
    if (telemetry_tick) {
        queue_telemetry(core, hal);
        /* held back by the schedule (<= 2 ms): the next frame is due one period after this one was */
        uint32_t late_ms = core->state.uptime_ms - core->state.telemetry_due_ms;
        late_ms = late_ms <= RW_CORE_SCHEDULE_MAX_HOLD_MS ? late_ms : 0u;
        core->state.telemetry_due_ms = core->state.uptime_ms + telemetry_period_ms(core) - late_ms;
    }
    bool idle_tick = !speed_tick && !telemetry_tick && !spindle_ran;
    if (idle_tick && rw_burst_streaming(&core->state.burst)) {
        /* one BURST_DATA frame into an empty outbox (after telemetry, events, replies); this tick's work is the
         * pack, as a telemetry tick's is, so it signs nothing */
        idle_tick = !queue_burst_frame(core);
    }
    send_queued(core, hal, sent, idle_tick);
}
