/* The spindle slot (every RW_CORE_SPINDLE_PERIOD_MS, on an "other" tick of the schedule, rw_core.h): the
 * servo's reading goes to the spindle position loop (rw_spindle.h), its outcome becomes events, faults and
 * grasp transitions, and the moving speed it asks for is written back (never while DISARMED, in ESTOP or in
 * FAULT, but for homing while DISARMED). */
#include "rw_core_internal.h"

void rw_core_spindle_step(rw_core *core, const rw_hal *hal, uint32_t elapsed_ms)
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
        rw_core_emit_event(core, RW_EVENT_KIND_SPINDLE_HOMED, st, st, RW_HOMED_BY_STALL);
        break;
    case RW_SPINDLE_HOMED_BY_SWITCH:
        rw_core_emit_event(core, RW_EVENT_KIND_SPINDLE_HOMED, st, st, RW_HOMED_BY_SWITCH);
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
