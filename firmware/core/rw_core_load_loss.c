/* The core's use of the load-loss monitor (rw_load_monitor.h): when it watches, and what the device does when
 * the load on the flying rope vanishes.
 *
 * Watched: AIRBORNE, the setpoint at its target (no ramp, no guard approach) and the speed PI not saturated;
 * anything else restarts the monitor, which learns the load anew once steady again (load_loss in
 * docs/load_loss.md gives the figures and what cannot be seen).
 *
 * On a loss: EVENT LOAD_LOST (arg = the drop, mN), fault LOAD_LOST (latched until DISARM; SET_ROPE_SPEED is
 * refused meanwhile) and a controlled spin-down (SPINDOWN, cause LOAD_LOST). Why land: the load vanished
 * either because the rope broke - an open rope end driven at up to 20 m/s whips about next to people and can
 * leave the guide - or because the object came off the loop, which the host asked the device to carry;
 * both need the operator, and a landed rope is safe in both. The spin-down (not ESC minimum at once, as in
 * ESTOP) keeps the drive in control of what rope is left in the wheels. */
#include <math.h>

#include "rw_core_internal.h"
#include "rw_float_bits.h"

/* Motors on the one ESC command (two, pinching the rope: docs/architecture.md, docs/drive_plant.md). */
#define RW_CORE_DRIVE_MOTOR_COUNT 2.0f

void rw_core_load_loss_apply_params(rw_core *core)
{
    const rw_params *p = &core->params;
    rw_load_monitor_config *c = &core->state.load_monitor.cfg;
    c->n_per_v = rw_load_monitor_n_per_v(RW_CORE_DRIVE_MOTOR_COUNT, rw_params_get(p, RW_PARAM_MOTOR_KV_RPM_PER_V),
                                         rw_params_get(p, RW_PARAM_DRIVE_RESISTANCE_OHM),
                                         rw_params_get(p, RW_PARAM_WHEEL_RADIUS_M));
    c->drop_n = rw_params_get(p, RW_PARAM_LOAD_LOSS_DROP_N);
    c->time_s = rw_params_get(p, RW_PARAM_LOAD_LOSS_TIME_S);
    rw_load_monitor_prepare(&core->state.load_monitor, RW_CORE_LOAD_CHECK_DT_S);
}

void rw_core_load_loss_step(rw_core *core)
{
    const float dt_s = RW_CORE_LOAD_CHECK_DT_S;
    const uint8_t st = core->state.state;
    /* "at its target" in the ramp's own Q16.16 (the float target, 15000 mm/s x 0.001, is 15.000001 m/s) */
    const rw_speed_loop *loop = &core->state.loop;
    const bool steady = st == RW_STATE_AIRBORNE && rw_ramp_at_target(&loop->ramp, core->state.target_mps) &&
                        loop->pi.state.saturation == 0;
    if (!rw_load_monitor_step_q16(&core->state.load_monitor, steady, rw_pi_controller_integral_q16(&loop->pi),
                                  rw_f32_to_q16(rw_speed_loop_battery_v(loop)), dt_s)) {
        return;
    }
    float drop_mn = rw_load_monitor_drop_n(&core->state.load_monitor) * 1000.0f;
    rw_core_emit_event(core, RW_EVENT_KIND_LOAD_LOST, st, st, drop_mn < 2.0e9f ? (int32_t)drop_mn : INT32_MAX);
    rw_core_raise_fault(core, RW_FAULT_LOAD_LOST);
    core->state.target_mps = 0.0f;
    rw_core_set_state(core, RW_STATE_SPINDOWN, RW_CAUSE_LOAD_LOST);
}
