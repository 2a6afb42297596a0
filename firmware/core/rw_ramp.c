/*
 * rw_ramp.c - setpoint rate limiter.
 */
#include "rw_ramp.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

void rw_ramp_init(rw_ramp *r, const rw_ramp_config *cfg)
{
    r->cfg = *cfg;
    r->state.step_up = 0.0f;
    r->state.step_up_rate_per_s = 0.0f;
    r->state.step_up_dt_s = 0.0f;
    r->state.step_down = 0.0f;
    r->state.step_down_rate_per_s = 0.0f;
    r->state.step_down_dt_s = 0.0f;
    rw_ramp_reset(r);
}

void rw_ramp_config_defaults(rw_ramp_config *cfg)
{
    cfg->rate_up_per_s = RW_DEFAULT_SPEED_RAMP_UP_MPS_PER_S;
    cfg->rate_down_per_s = RW_DEFAULT_SPEED_RAMP_DOWN_MPS_PER_S;
}

void rw_ramp_reset(rw_ramp *r)
{
    r->state.y = 0.0f;
}

void rw_ramp_reset_to(rw_ramp *r, float y)
{
    r->state.y = rw_f32_finite(y) ? y : 0.0f;
}

float rw_ramp_output(const rw_ramp *r)
{
    return r->state.y;
}

bool rw_ramp_at_target(const rw_ramp *r, float target)
{
    /* Exact on purpose: the step lands on the target exactly (written so -Wfloat-equal is quiet). */
    return !rw_f32_lt(r->state.y, target) && !rw_f32_gt(r->state.y, target) && rw_f32_finite(target);
}

bool rw_ramp_config_is_valid(const rw_ramp_config *cfg)
{
    return rw_f32_finite(cfg->rate_up_per_s) && rw_f32_finite(cfg->rate_down_per_s);
}

/*
 * Discrete law (per step of dt_s seconds):
 *     d    = target - y[k-1]
 *     y[k] = y[k-1] + min(d,  rate_up_per_s   * dt_s)   if d > 0
 *     y[k] = y[k-1] - min(-d, rate_down_per_s * dt_s)   if d < 0
 * so the output reaches the target exactly (no overshoot, no chatter) and moves by exactly
 * rate * dt_s per step while it is further away than that. A rate <= 0 or not finite: no limit in
 * that direction (y[k] = target).
 * dt_s <= 0, dt_s not finite or target not finite: y[k] = y[k-1].
 * rate * dt_s is computed once per (rate, dt_s), for each direction when the ramp first moves that way,
 * and kept: the same value, bit for bit, as computing it every step (a caller that changes the fall rate
 * while rising pays nothing for it); the comparisons run on the bit patterns (rw_float_bits.h), with the
 * C semantics.
 */
float rw_ramp_step(rw_ramp *r, float target, float dt_s)
{
    if (!rw_f32_finite(target) || !rw_f32_positive_finite(dt_s)) {
        return r->state.y;
    }
    const float y = r->state.y;
    const float d = target - y;
    if (!rw_f32_finite(d)) { /* target and y of opposite sign near FLT_MAX */
        return r->state.y;
    }
    if (rw_f32_positive(d)) {
        const float rate_up = r->cfg.rate_up_per_s;
        if (!rw_f32_same(dt_s, r->state.step_up_dt_s) || !rw_f32_same(rate_up, r->state.step_up_rate_per_s)) {
            r->state.step_up = rate_up * dt_s;
            r->state.step_up_rate_per_s = rate_up;
            r->state.step_up_dt_s = dt_s;
        }
        const float max_step = r->state.step_up;
        r->state.y = (rw_f32_positive(rate_up) && rw_f32_finite(max_step) && rw_f32_gt(d, max_step)) ? y + max_step
                                                                                                      : target;
    } else if (rw_f32_lt(d, 0.0f)) {
        const float rate_down = r->cfg.rate_down_per_s;
        if (!rw_f32_same(dt_s, r->state.step_down_dt_s) || !rw_f32_same(rate_down, r->state.step_down_rate_per_s)) {
            r->state.step_down = rate_down * dt_s;
            r->state.step_down_rate_per_s = rate_down;
            r->state.step_down_dt_s = dt_s;
        }
        const float max_step = r->state.step_down;
        r->state.y = (rw_f32_positive(rate_down) && rw_f32_finite(max_step) && rw_f32_gt(-d, max_step)) ? y - max_step
                                                                                                          : target;
    }
    return r->state.y;
}
