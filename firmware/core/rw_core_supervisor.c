/* The supervisor: the device state machine and its safety checks, every tick (step 3 of rw_core_tick).
 *
 * Transitions and why (the causes are the protocol's enum cause; each change emits STATE_CHANGED):
 *   heartbeat lost      SPINUP/AIRBORNE -> SPINDOWN, RETRACT -> ARMED, RELAX lands without retracting; the
 *                       spindle stops (no guide move goes on without a host)
 *   battery low         under battery_cutoff_v for battery_cutoff_time_s: fault BATTERY_LOW, SPINUP/AIRBORNE
 *                       -> SPINDOWN
 *   encoder silent      no edge for encoder_timeout_s while the throttle is up: fault ENCODER_SILENT -> FAULT
 *                       (the only fault that stops the state machine: a blind speed loop)
 *   ToV guard           AIRBORNE: under ToV for collapse_time_s -> LOOP_COLLAPSED, SPINUP; SPINUP: target and
 *                       speed at the guard -> AIRBORNE
 *   landed              SPINDOWN at 0 -> ARMED; RELAX (grasp) at 0 -> RETRACT
 * Commands (rw_core_commands.c), the spindle slot (rw_core_spindle.c) and the load-loss check
 * (rw_core_load_loss.c) change state through rw_core_set_state and rw_core_raise_fault as well.
 * The time thresholds are compared on float bit patterns (rw_float_bits.h): no soft-float call per tick.
 */
#include "rw_core_internal.h"
#include "rw_float_bits.h"
#include "rw_wire_units.h"

void rw_core_set_state(rw_core *core, uint8_t new_state, uint8_t cause)
{
    uint8_t old = core->state.state;
    if (old == new_state) {
        return;
    }
    core->state.state = new_state;
    if (new_state == RW_STATE_SPINUP && (old == RW_STATE_ARMED)) {
        rw_speed_loop_start(&core->state.loop);
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

rw_speed_loop_mode rw_core_speed_loop_mode(uint8_t state)
{
    switch (state) {
    case RW_STATE_SPINUP:
        return RW_SPEED_LOOP_DRIVE;
    case RW_STATE_AIRBORNE:
        return RW_SPEED_LOOP_AIRBORNE;
    case RW_STATE_SPINDOWN: /* a commanded or forced landing */
    case RW_STATE_RELAX:
        return RW_SPEED_LOOP_LAND;
    default: /* DISARMED, ARMED, FAULT, ESTOP, RETRACT, HOLD: the rope is not driven */
        return RW_SPEED_LOOP_OFF;
    }
}

void rw_core_supervise(rw_core *core, float dt_s, uint32_t dt_ms, uint32_t encoder_counts_delta)
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
    uint16_t esc_min = core->state.loop.throttle.cfg.pulse_min_us; /* (uint16_t)esc_min_us (rw_core_apply_params) */
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
                               (int32_t)rw_wire_u16_times(core->state.measured_mps, 125u, 3)); /* x 1000 */
            rw_core_set_state(core, RW_STATE_SPINUP, RW_CAUSE_LOOP_COLLAPSED);
        }
    } else if (st == RW_STATE_SPINUP && rw_f32_ge(core->state.target_mps, guard_mps) &&
               rw_f32_ge(core->state.measured_mps, guard_mps)) {
        rw_core_set_state(core, RW_STATE_AIRBORNE, RW_CAUSE_SPEED_REACHED);
    } else if (st == RW_STATE_SPINDOWN && rw_ramp_output_q16(&core->state.loop.ramp) <= 0 &&
               rw_f32_lt(core->state.measured_mps, RW_CORE_STOPPED_MPS)) {
        rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_SPEED_REACHED);
    } else if (st == RW_STATE_RELAX && core->state.grasp_pending && rw_ramp_output_q16(&core->state.loop.ramp) <= 0 &&
               rw_f32_lt(core->state.measured_mps, RW_CORE_STOPPED_MPS)) {
        core->state.grasp_pending = false;
        rw_spindle_retract(&core->state.spindle);
        rw_core_set_state(core, RW_STATE_RETRACT, RW_CAUSE_SPEED_REACHED);
    }
}
