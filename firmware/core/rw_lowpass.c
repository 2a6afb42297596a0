/*
 * rw_lowpass.c - first-order low-pass filter.
 */
#include "rw_lowpass.h"

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

void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg)
{
    f->cfg = *cfg;
    rw_lowpass_reset(f);
}

void rw_lowpass_reset(rw_lowpass *f)
{
    f->state.y = 0.0f;
}

void rw_lowpass_reset_to(rw_lowpass *f, float y)
{
    f->state.y = finite_f(y) ? y : 0.0f;
}

float rw_lowpass_output(const rw_lowpass *f)
{
    return f->state.y;
}

bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg)
{
    return finite_f(cfg->tau_s) && cfg->tau_s >= 0.0f;
}

/*
 * Continuous law:   tau * dy/dt + y = x
 * Discrete law (backward Euler, unconditionally stable for any dt_s > 0, no exp() on the M0+):
 *     alpha = dt_s / (tau_s + dt_s)          0 < alpha <= 1
 *     y[k]  = y[k-1] + alpha * (x[k] - y[k-1])
 * tau_s <= 0 (or not finite): y[k] = x[k] (pass-through).
 * dt_s <= 0, dt_s not finite or x not finite: y[k] = y[k-1] (the sample is ignored), so no NaN or
 * infinity ever leaves the filter.
 */
float rw_lowpass_step(rw_lowpass *f, float x, float dt_s)
{
    if (!finite_f(x) || !finite_f(dt_s) || dt_s <= 0.0f) {
        return f->state.y;
    }
    const float tau_s = f->cfg.tau_s;
    if (!(tau_s > 0.0f) || !finite_f(tau_s)) {
        f->state.y = x;
        return f->state.y;
    }
    const float alpha = dt_s / (tau_s + dt_s);
    const float y = f->state.y + alpha * (x - f->state.y);
    if (finite_f(y)) { /* x - y may overflow for inputs near FLT_MAX */
        f->state.y = y;
    }
    return f->state.y;
}
