/*
 * rw_lowpass.c - first-order low-pass filter.
 */
#include "rw_lowpass.h"

#include "rw_float_bits.h"

void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg)
{
    f->cfg = *cfg;
    f->state.alpha = 1.0f;
    f->state.alpha_tau_s = 0.0f;
    f->state.alpha_dt_s = 0.0f;
    rw_lowpass_reset(f);
}

void rw_lowpass_reset(rw_lowpass *f)
{
    f->state.y = 0.0f;
}

void rw_lowpass_reset_to(rw_lowpass *f, float y)
{
    f->state.y = rw_f32_finite(y) ? y : 0.0f;
}

float rw_lowpass_output(const rw_lowpass *f)
{
    return f->state.y;
}

bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg)
{
    return rw_f32_finite(cfg->tau_s) && rw_f32_ge(cfg->tau_s, 0.0f);
}

/*
 * Continuous law:   tau * dy/dt + y = x
 * Discrete law (backward Euler, unconditionally stable for any dt_s > 0, no exp() on the M0+):
 *     alpha = dt_s / (tau_s + dt_s)          0 < alpha <= 1
 *     y[k]  = y[k-1] + alpha * (x[k] - y[k-1])
 * tau_s <= 0 (or not finite): y[k] = x[k] (pass-through).
 * dt_s <= 0, dt_s not finite or x not finite: y[k] = y[k-1] (the sample is ignored), so no NaN or
 * infinity ever leaves the filter.
 * alpha is computed once per (tau_s, dt_s) pair and kept (a division is ~350 instructions on the M0+;
 * the tick has a fixed dt): the same value, bit for bit, as computing it every step.
 */
float rw_lowpass_step(rw_lowpass *f, float x, float dt_s)
{
    if (!rw_f32_finite(x) || !rw_f32_positive_finite(dt_s)) {
        return f->state.y;
    }
    const float tau_s = f->cfg.tau_s;
    if (!rw_f32_positive_finite(tau_s)) {
        f->state.y = x;
        return f->state.y;
    }
    if (!rw_f32_same(tau_s, f->state.alpha_tau_s) || !rw_f32_same(dt_s, f->state.alpha_dt_s)) {
        f->state.alpha = dt_s / (tau_s + dt_s);
        f->state.alpha_tau_s = tau_s;
        f->state.alpha_dt_s = dt_s;
    }
    const float alpha = f->state.alpha;
    const float y = f->state.y + alpha * (x - f->state.y);
    if (rw_f32_finite(y)) { /* x - y may overflow for inputs near FLT_MAX */
        f->state.y = y;
    }
    return f->state.y;
}
