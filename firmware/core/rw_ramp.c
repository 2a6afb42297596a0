/*
 * rw_ramp.c - setpoint rate limiter, Q16.16 fixed point.
 */
#include "rw_ramp.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

void rw_ramp_init(rw_ramp *r, const rw_ramp_config *cfg)
{
    r->cfg = *cfg;
    rw_ramp_prepare(r, 0.0f);
    rw_ramp_reset(r);
}

void rw_ramp_config_defaults(rw_ramp_config *cfg)
{
    cfg->rate_up_per_s = RW_DEFAULT_SPEED_RAMP_UP_MPS_PER_S;
    cfg->rate_down_per_s = RW_DEFAULT_SPEED_RAMP_DOWN_MPS_PER_S;
}

void rw_ramp_reset(rw_ramp *r)
{
    r->state.y_q32 = 0;
}

void rw_ramp_reset_to(rw_ramp *r, float y)
{
    r->state.y_q32 = (int64_t)(rw_f32_finite(y) ? rw_f32_to_q16(y) : 0) * 65536;
}

float rw_ramp_output(const rw_ramp *r)
{
    return rw_f32_from_q16(rw_ramp_output_q16(r));
}

int32_t rw_ramp_output_q16(const rw_ramp *r)
{
    return (int32_t)((r->state.y_q32 + 32768) >> 16); /* rounded to nearest */
}

bool rw_ramp_at_target(const rw_ramp *r, float target)
{
    return rw_f32_finite(target) && r->state.y_q32 == (int64_t)rw_f32_to_q16(target) * 65536;
}

bool rw_ramp_config_is_valid(const rw_ramp_config *cfg)
{
    return rw_f32_finite(cfg->rate_up_per_s) && rw_f32_finite(cfg->rate_down_per_s);
}

/* rate * dt_s in Q32 (the Q16 part plus the rounded remainder, both by the bit-pattern conversion: no
 * float -> int64 conversion, which would link double-precision code), at least 2^-32; INT64_MAX (no limit)
 * for a rate <= 0, not finite, or a step beyond the Q16 range. In rw_ramp_prepare (or a step of another dt_s). */
static int64_t step_q32(float rate_per_s, float dt_s)
{
    if (!rw_f32_positive_finite(rate_per_s)) {
        return INT64_MAX;
    }
    const float step = rate_per_s * dt_s;
    const int32_t whole_q16 = rw_f32_to_q16(step);
    if (whole_q16 == INT32_MAX) {
        return INT64_MAX;
    }
    const int32_t rest_q32 = rw_f32_to_q16((step - rw_f32_from_q16(whole_q16)) * 65536.0f); /* |rest| <= 1/2 LSB */
    const int64_t total = (int64_t)whole_q16 * 65536 + rest_q32;
    return total < 1 ? 1 : total;
}

void rw_ramp_prepare(rw_ramp *r, float dt_s)
{
    const bool usable = rw_f32_positive_finite(dt_s);
    r->state.step_up_q32 = usable ? step_q32(r->cfg.rate_up_per_s, dt_s) : INT64_MAX;
    r->state.step_down_q32 = usable ? step_q32(r->cfg.rate_down_per_s, dt_s) : INT64_MAX;
    r->state.prepared_dt_s = usable ? dt_s : 0.0f;
}

/*
 * Discrete law (per step of dt_s seconds), in integers (Q32: units x 2^32):
 *     d    = target - y[k-1]
 *     y[k] = y[k-1] + min(d,  step_up)     if d > 0,     step_up   = rate_up_per_s   * dt_s
 *     y[k] = y[k-1] - min(-d, step_down)   if d < 0,     step_down = rate_down_per_s * dt_s
 * so the output reaches the target exactly (no overshoot, no chatter) and moves by exactly one step
 * while it is further away than that. A rate <= 0 or not finite: no limit in that direction
 * (y[k] = target). dt_s <= 0 or not finite: y[k] = y[k-1].
 * The steps come from rw_ramp_prepare for the dt_s the caller steps with; another dt_s converts its own.
 */
int32_t rw_ramp_step(rw_ramp *r, int32_t target_q16, float dt_s)
{
    if (!rw_f32_positive_finite(dt_s)) {
        return rw_ramp_output_q16(r);
    }
    const int64_t target = (int64_t)target_q16 * 65536;
    const int64_t y = r->state.y_q32;
    const int64_t d = target - y; /* |d| < 2^48 */
    const bool prepared = rw_f32_same(dt_s, r->state.prepared_dt_s);
    if (d > 0) {
        const int64_t step = prepared ? r->state.step_up_q32 : step_q32(r->cfg.rate_up_per_s, dt_s);
        r->state.y_q32 = d > step ? y + step : target;
    } else if (d < 0) {
        const int64_t step = prepared ? r->state.step_down_q32 : step_q32(r->cfg.rate_down_per_s, dt_s);
        r->state.y_q32 = -d > step ? y - step : target;
    }
    return rw_ramp_output_q16(r);
}
