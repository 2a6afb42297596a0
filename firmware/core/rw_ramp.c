/*
 * rw_ramp.c - setpoint rate limiter.
 */
#include "rw_ramp.h"

#include "rw_defaults.h"

#include <stdint.h>
#include <string.h>

/* Finite test on the bit pattern (exponent not all ones): isfinite() costs two soft-float library
 * calls on the Cortex-M0+, this is a few integer instructions. */
static bool finite_f(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return (bits & 0x7F800000u) != 0x7F800000u;
}

void rw_ramp_init(rw_ramp *r, const rw_ramp_config *cfg)
{
    r->cfg = *cfg;
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
    r->state.y = finite_f(y) ? y : 0.0f;
}

float rw_ramp_output(const rw_ramp *r)
{
    return r->state.y;
}

bool rw_ramp_at_target(const rw_ramp *r, float target)
{
    /* Exact on purpose: the step lands on the target exactly (written so -Wfloat-equal is quiet). */
    return !(r->state.y < target) && !(r->state.y > target) && finite_f(target);
}

bool rw_ramp_config_is_valid(const rw_ramp_config *cfg)
{
    return finite_f(cfg->rate_up_per_s) && finite_f(cfg->rate_down_per_s);
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
 */
float rw_ramp_step(rw_ramp *r, float target, float dt_s)
{
    if (!finite_f(target) || !finite_f(dt_s) || dt_s <= 0.0f) {
        return r->state.y;
    }
    const float y = r->state.y;
    const float d = target - y;
    if (!finite_f(d)) { /* target and y of opposite sign near FLT_MAX */
        return r->state.y;
    }
    if (d > 0.0f) {
        const float rate = r->cfg.rate_up_per_s;
        const float max_step = rate * dt_s;
        r->state.y = (rate > 0.0f && finite_f(max_step) && d > max_step) ? y + max_step : target;
    } else if (d < 0.0f) {
        const float rate = r->cfg.rate_down_per_s;
        const float max_step = rate * dt_s;
        r->state.y = (rate > 0.0f && finite_f(max_step) && -d > max_step) ? y - max_step : target;
    }
    return r->state.y;
}
