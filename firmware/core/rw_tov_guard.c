/*
 * rw_tov_guard.c - takeoff velocity guard: airborne setpoint check and collapse detector.
 */
#include "rw_tov_guard.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

void rw_tov_guard_prepare(rw_tov_guard *g)
{
    g->state.min_airborne_mps = g->cfg.tov_mps * g->cfg.margin;
    g->state.min_airborne_mps_q16 = rw_f32_to_q16(g->state.min_airborne_mps);
    g->state.config_valid = rw_tov_guard_config_is_valid(&g->cfg);
}

void rw_tov_guard_init(rw_tov_guard *g, const rw_tov_guard_config *cfg)
{
    g->cfg = *cfg;
    rw_tov_guard_prepare(g);
    rw_tov_guard_reset(g);
}

void rw_tov_guard_config_defaults(rw_tov_guard_config *cfg)
{
    cfg->tov_mps = RW_DEFAULT_TOV_MPS;
    cfg->margin = RW_DEFAULT_TOV_MARGIN;
    cfg->collapse_time_s = RW_DEFAULT_COLLAPSE_TIME_S;
}

void rw_tov_guard_reset(rw_tov_guard *g)
{
    g->state.below_s = 0.0f;
    g->state.collapsed = false;
}

bool rw_tov_guard_config_is_valid(const rw_tov_guard_config *cfg)
{
    return rw_f32_positive_finite(cfg->tov_mps) && rw_f32_finite(cfg->margin) && rw_f32_ge(cfg->margin, 1.0f) &&
           rw_f32_finite(cfg->collapse_time_s) && rw_f32_ge(cfg->collapse_time_s, 0.0f);
}

float rw_tov_guard_min_airborne_mps(const rw_tov_guard *g)
{
    return g->state.min_airborne_mps;
}

int32_t rw_tov_guard_min_airborne_mps_q16(const rw_tov_guard *g)
{
    return g->state.min_airborne_mps_q16;
}

bool rw_tov_guard_setpoint_allowed(const rw_tov_guard *g, float setpoint_mps)
{
    if (!g->state.config_valid || !rw_f32_finite(setpoint_mps)) {
        return false;
    }
    return rw_f32_ge(setpoint_mps, rw_tov_guard_min_airborne_mps(g));
}

bool rw_tov_guard_is_collapsed(const rw_tov_guard *g)
{
    return g->state.collapsed;
}

/*
 * Discrete law (step k, dt = dt_s):
 *   v[k] >= tov_mps:  below := 0, collapsed := false              (recovered: detector re-armed)
 *   v[k] <  tov_mps:  below := below + dt
 *                     if not collapsed and below >= collapse_time_s: collapsed := true, report once
 * The timer counts continuous time under ToV: any sample at or above ToV restarts it.
 * dt_s <= 0 or not finite: the timer does not advance (a recovery still re-arms).
 * v[k] not finite: ignored (no advance, no re-arm). Invalid config: never reports.
 */
bool rw_tov_guard_step(rw_tov_guard *g, float measured_mps, float dt_s)
{
    if (!rw_f32_finite(measured_mps) || !g->state.config_valid) {
        return false;
    }
    if (rw_f32_ge(measured_mps, g->cfg.tov_mps)) {
        g->state.below_s = 0.0f;
        g->state.collapsed = false;
        return false;
    }
    if (rw_f32_positive_finite(dt_s) && rw_f32_lt(g->state.below_s, g->cfg.collapse_time_s)) {
        g->state.below_s += dt_s; /* stops counting once past the threshold: no float growth */
    }
    if (!g->state.collapsed && rw_f32_ge(g->state.below_s, g->cfg.collapse_time_s)) {
        g->state.collapsed = true;
        return true;
    }
    return false;
}
