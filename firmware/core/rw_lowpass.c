/*
 * rw_lowpass.c - first-order low-pass filter, fixed point.
 */
#include "rw_lowpass.h"

#include "rw_float_bits.h"

#define RW_LOWPASS_ALPHA_ONE_Q20 (1 << 20)
/* |x - y| is clamped to this many units (Q32: 2^42 = 1024 units) before the multiply by alpha (Q20): the
 * product stays within 64 bits; a larger jump is followed in several steps. */
#define RW_LOWPASS_MAX_STEP_Q32 ((int64_t)1 << 42)

void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg)
{
    f->cfg = *cfg;
    rw_lowpass_prepare(f, 0.0f);
    rw_lowpass_reset(f);
}

void rw_lowpass_reset(rw_lowpass *f)
{
    f->state.y_q32 = 0;
}

void rw_lowpass_reset_to(rw_lowpass *f, int32_t y_q16)
{
    f->state.y_q32 = (int64_t)y_q16 * 65536;
}

int32_t rw_lowpass_output_q16(const rw_lowpass *f)
{
    return (int32_t)((f->state.y_q32 + 32768) >> 16);
}

bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg)
{
    return rw_f32_finite(cfg->tau_s) && rw_f32_ge(cfg->tau_s, 0.0f);
}

/* dt / (tau + dt) in Q20, at least 2^-20, for tau_s and dt_s both finite and > 0 (one float division). */
static int32_t alpha_q20_of(float tau_s, float dt_s)
{
    const int32_t alpha_q20 = rw_f32_to_q16(dt_s / (tau_s + dt_s) * 16.0f); /* Q16 of 16 alpha = Q20 */
    return alpha_q20 < 1 ? 1 : (alpha_q20 > RW_LOWPASS_ALPHA_ONE_Q20 ? RW_LOWPASS_ALPHA_ONE_Q20 : alpha_q20);
}

void rw_lowpass_prepare(rw_lowpass *f, float dt_s)
{
    const bool usable = rw_f32_positive_finite(dt_s) && rw_f32_positive_finite(f->cfg.tau_s);
    f->state.alpha_q20 = usable ? alpha_q20_of(f->cfg.tau_s, dt_s) : RW_LOWPASS_ALPHA_ONE_Q20;
    f->state.prepared_dt_s = usable ? dt_s : 0.0f;
}

/*
 * Continuous law:   tau * dy/dt + y = x
 * Discrete law (backward Euler, unconditionally stable for any dt_s > 0, no exp() on the M0+):
 *     alpha = dt_s / (tau_s + dt_s)          0 < alpha <= 1   (Q20, at least 2^-20)
 *     y[k]  = y[k-1] + alpha * (x[k] - y[k-1])                 (y kept in Q32, so no dead band)
 * tau_s <= 0 (or not finite): y[k] = x[k] (pass-through).
 * dt_s <= 0 or not finite: y[k] = y[k-1] (the sample is ignored).
 * alpha is computed by rw_lowpass_prepare for the step the caller makes (a division is ~350 instructions on
 * the M0+; the tick has a fixed dt); a step of another dt computes its own. The step is integer arithmetic.
 */
int32_t rw_lowpass_step(rw_lowpass *f, int32_t x_q16, float dt_s)
{
    if (!rw_f32_positive_finite(dt_s)) {
        return rw_lowpass_output_q16(f);
    }
    const float tau_s = f->cfg.tau_s;
    if (!rw_f32_positive_finite(tau_s)) {
        rw_lowpass_reset_to(f, x_q16);
        return x_q16;
    }
    const int32_t alpha_q20 = rw_f32_same(dt_s, f->state.prepared_dt_s) ? f->state.alpha_q20 : alpha_q20_of(tau_s, dt_s);
    if (alpha_q20 == RW_LOWPASS_ALPHA_ONE_Q20) { /* dt far beyond tau */
        rw_lowpass_reset_to(f, x_q16);
        return x_q16;
    }
    int64_t e = (int64_t)x_q16 * 65536 - f->state.y_q32;
    e = e > RW_LOWPASS_MAX_STEP_Q32 ? RW_LOWPASS_MAX_STEP_Q32 : (e < -RW_LOWPASS_MAX_STEP_Q32 ? -RW_LOWPASS_MAX_STEP_Q32 : e);
    /* e alpha (|e| <= 2^42, alpha < 2^20) from 32-bit pieces, inline: e = e_hi 2^32 + e_lo with |e_hi| <= 2^10, so
     * e_hi alpha fits 32 bits (libgcc's 64 x 64 multiply is a call of ~40 instructions on the Cortex-M0+) */
    const int32_t e_hi = (int32_t)(e >> 32);
    const uint32_t e_lo = (uint32_t)e;
    const int64_t product = (int64_t)((uint64_t)(uint32_t)(e_hi * alpha_q20) << 32) +
                            (int64_t)rw_mul_u32_u64(e_lo, (uint32_t)alpha_q20);
    f->state.y_q32 += product >> 20;
    return rw_lowpass_output_q16(f);
}
