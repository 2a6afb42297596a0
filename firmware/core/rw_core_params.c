/* Parameters into the controllers: which modules a change feeds, and when they are converted (prepared).
 *
 * A full conversion (rw_core_apply_params: every module) runs at init and when the stored record is loaded.
 * A PARAM_SET (rw_core_set_param) is staged instead: the value is checked and stored at once (the ACK, the
 * PARAM_VALUE and every later check see it), and the modules it feeds (rw_params_modules) are marked
 * pending. The tick converts one pending module at its end (rw_core_params_tick_end), on a tick that took no
 * datagram, so a tick carries either a command (its tag check, execution and signed ACK) or one module's
 * float work, never both: the speed step of the next tick sees that module's old or new values, never a mix.
 * A module left pending RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS ticks (datagrams in every tick) is converted
 * anyway. The modules the command checks read (the ToV guard: SET_ROPE_SPEED; the spindle: HOME, SET_LOOP,
 * GRASP, RELEASE, RETRACT) are converted before a command executes (rw_core_params_settle; each costs a
 * few multiplications), so no command is checked against a value that a PARAM_SET already replaced. */
#include "rw_core_internal.h"

/* The controllers are prepared for the nominal periods of the schedule (rw_core.c). */
#define RW_CORE_PARAMS_SPEED_DT_S ((float)(2u * RW_CORE_TICK_US) * 1.0e-6f)

static void prepare_estimator(rw_core *core)
{
    const rw_params *p = &core->params;
    rw_mt_speed_estimator_config *est = &core->state.loop.estimator.cfg;
    est->counts_per_rev = (uint32_t)rw_params_get(p, RW_PARAM_ENCODER_COUNTS_PER_REV);
    est->timeout_us = (uint32_t)(rw_params_get(p, RW_PARAM_ENCODER_TIMEOUT_S) * 1.0e6f);
    est->wheel_radius_m = rw_params_get(p, RW_PARAM_WHEEL_RADIUS_M);
    est->filter_tau_s = rw_params_get(p, RW_PARAM_SPEED_FILTER_TAU_S);
    rw_speed_loop_prepare_estimator(&core->state.loop, RW_CORE_PARAMS_SPEED_DT_S);
}

static void prepare_ramp(rw_core *core)
{
    rw_speed_loop *loop = &core->state.loop;
    loop->ramp.cfg.rate_up_per_s = rw_params_get(&core->params, RW_PARAM_RAMP_UP_MPS2);
    loop->ramp.cfg.rate_down_per_s = rw_params_get(&core->params, RW_PARAM_RAMP_DOWN_MPS2);
    rw_speed_loop_prepare_ramp(loop, RW_CORE_PARAMS_SPEED_DT_S);
}

/* The PI's lower limit in force (the airborne floor, set by the speed step) is kept: a prepare puts out_min
 * back to cfg.out_min (0), which the next speed step replaces. */
static void prepare_pi(rw_core *core)
{
    rw_speed_loop *loop = &core->state.loop;
    loop->pi.cfg.kp = rw_params_get(&core->params, RW_PARAM_SPEED_KP);
    loop->pi.cfg.ki_per_s = rw_params_get(&core->params, RW_PARAM_SPEED_KI);
    loop->pi.cfg.out_min = 0.0f;
    loop->pi.cfg.out_max = 1.0f;
    rw_speed_loop_prepare_pi(loop, RW_CORE_PARAMS_SPEED_DT_S);
}

static void prepare_throttle(rw_core *core)
{
    rw_speed_loop *loop = &core->state.loop;
    loop->throttle.cfg.kv_rpm_per_v = rw_params_get(&core->params, RW_PARAM_MOTOR_KV_RPM_PER_V);
    loop->throttle.cfg.wheel_radius_m = rw_params_get(&core->params, RW_PARAM_WHEEL_RADIUS_M);
    loop->throttle.cfg.pulse_min_us = (uint16_t)rw_params_get(&core->params, RW_PARAM_ESC_MIN_US);
    loop->throttle.cfg.pulse_max_us = (uint16_t)RW_ESC_PULSE_MAX_US;
    rw_speed_loop_prepare_throttle(loop);
}

/* The guard and the speed loop's airborne floor change together. */
static void prepare_tov_guard(rw_core *core)
{
    rw_tov_guard *guard = &core->state.guard;
    guard->cfg.tov_mps = rw_params_get(&core->params, RW_PARAM_TOV_MPS);
    guard->cfg.margin = rw_params_get(&core->params, RW_PARAM_TOV_MARGIN);
    guard->cfg.collapse_time_s = rw_params_get(&core->params, RW_PARAM_COLLAPSE_TIME_S);
    rw_tov_guard_prepare(guard);
    core->state.loop.cfg.guard_mps = rw_tov_guard_min_airborne_mps(guard);
    rw_speed_loop_prepare_guard(&core->state.loop);
}

/* The spindle derives what it needs from its config itself (rw_spindle.h: memo_cfg). */
static void prepare_spindle(rw_core *core)
{
    const rw_params *p = &core->params;
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
}

/* The new period starts now. */
static void prepare_telemetry(rw_core *core)
{
    core->state.telemetry_period_ms = rw_core_telemetry_period_ms(core);
    core->state.telemetry_due_ms = core->state.uptime_ms;
}

/* One entry per RW_PARAM_MODULE_* bit, lowest first (the order a staged change is converted in). */
static void (*const PREPARE[])(rw_core *core) = {
    prepare_estimator, prepare_ramp,  prepare_pi, prepare_throttle, prepare_tov_guard,
    prepare_spindle,   rw_core_load_loss_apply_params, prepare_telemetry,
};
_Static_assert(sizeof PREPARE / sizeof PREPARE[0] == 8u && RW_PARAM_MODULE_ALL == 0xFFu,
               "one prepare per RW_PARAM_MODULE_* bit");

void rw_core_prepare_modules(rw_core *core, uint16_t modules)
{
    for (unsigned bit = 0u; bit < sizeof PREPARE / sizeof PREPARE[0]; ++bit) {
        if ((modules & (1u << bit)) != 0u) {
            PREPARE[bit](core);
        }
    }
    core->state.params_pending &= (uint16_t)~modules;
}

void rw_core_apply_params(rw_core *core)
{
    rw_core_prepare_modules(core, RW_PARAM_MODULE_ALL);
}

int rw_core_set_param(rw_core *core, uint8_t param_id, float value)
{
    int result = rw_params_set(&core->params, param_id, value, core->state.state == RW_STATE_DISARMED);
    if (result == RW_DECODE_OK) {
        core->state.params_pending |= rw_params_modules(param_id);
    }
    return result;
}

void rw_core_params_settle(rw_core *core, uint16_t modules)
{
    const uint16_t due = (uint16_t)(core->state.params_pending & modules);
    if (due != 0u) {
        rw_core_prepare_modules(core, due);
    }
}

void rw_core_params_settle_all(rw_core *core)
{
    rw_core_params_settle(core, RW_PARAM_MODULE_ALL);
}

uint16_t rw_core_params_pending(const rw_core *core)
{
    return core->state.params_pending;
}

void rw_core_params_tick_end(rw_core *core)
{
    const bool took_datagram = core->state.took_datagram;
    core->state.took_datagram = false;
    const uint16_t pending = core->state.params_pending;
    if (pending == 0u) {
        return;
    }
    if (took_datagram && core->state.params_pending_ticks < RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS) {
        ++core->state.params_pending_ticks;
        return;
    }
    const uint16_t lowest = (uint16_t)(pending & (uint16_t)(~pending + 1u));
    rw_core_prepare_modules(core, lowest);
    core->state.params_pending_ticks = 0u;
}
