/*
 * rw_pi_controller.c - PI controller with feed-forward and anti-windup.
 */
#include "rw_pi_controller.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

void rw_pi_controller_init(rw_pi_controller *c, const rw_pi_controller_config *cfg)
{
    c->cfg = *cfg;
    c->state.ki_dt = 0.0f;
    c->state.ki_dt_ki_per_s = 0.0f;
    c->state.ki_dt_dt_s = 0.0f;
    rw_pi_controller_reset(c);
}

void rw_pi_controller_config_defaults(rw_pi_controller_config *cfg)
{
    cfg->kp = RW_DEFAULT_SPEED_KP;
    cfg->ki_per_s = RW_DEFAULT_SPEED_KI_PER_S;
    cfg->out_min = RW_DEFAULT_SPEED_OUT_MIN;
    cfg->out_max = RW_DEFAULT_SPEED_OUT_MAX;
}

void rw_pi_controller_reset(rw_pi_controller *c)
{
    c->state.integral = 0.0f;
    c->state.output = 0.0f;
    c->state.saturation = 0;
    /* Keep the held output inside the limits when 0 is not (e.g. out_min = 0.1). */
    if (rw_f32_lt(c->state.output, c->cfg.out_min)) {
        c->state.output = c->cfg.out_min;
    }
    if (rw_f32_gt(c->state.output, c->cfg.out_max)) {
        c->state.output = c->cfg.out_max;
    }
}

float rw_pi_controller_output(const rw_pi_controller *c)
{
    return c->state.output;
}

bool rw_pi_controller_config_is_valid(const rw_pi_controller_config *cfg)
{
    return rw_f32_finite(cfg->kp) && rw_f32_ge(cfg->kp, 0.0f) && rw_f32_finite(cfg->ki_per_s) &&
           rw_f32_ge(cfg->ki_per_s, 0.0f) && rw_f32_finite(cfg->out_min) && rw_f32_finite(cfg->out_max) &&
           rw_f32_le(cfg->out_min, cfg->out_max);
}

static float clampf(float x, float lo, float hi)
{
    return rw_f32_lt(x, lo) ? lo : (rw_f32_gt(x, hi) ? hi : x);
}

/* fmaxf/fminf as C99 defines them (a NaN argument gives the other one), compared on the bit patterns. */
static float maxf(float a, float b)
{
    if (rw_f32_isnan(a)) {
        return b;
    }
    if (rw_f32_isnan(b)) {
        return a;
    }
    return rw_f32_lt(a, b) ? b : a;
}

static float minf(float a, float b)
{
    if (rw_f32_isnan(a)) {
        return b;
    }
    if (rw_f32_isnan(b)) {
        return a;
    }
    return rw_f32_gt(a, b) ? b : a;
}

/*
 * Continuous law:   u(t) = ff(t) + kp * e(t) + ki * integral(e dt),   e = setpoint - measurement
 * Discrete law (forward-Euler integral, step k, dt = dt_s):
 *     e[k]  = setpoint[k] - measurement[k]
 *     p[k]  = kp * e[k]
 *     I'    = I[k-1] + ki_per_s * dt * e[k]                       (candidate integral)
 *     v     = ff[k] + p[k] + I'                                    (unsaturated output)
 * Anti-windup, two parts:
 *  1. conditional integration: if v > out_max and e[k] > 0, the integral only grows as far as
 *     the limit and never backwards, I' = max(I[k-1], out_max - ff[k] - p[k]) (symmetrically
 *     I' = min(I[k-1], out_min - ff[k] - p[k]) if v < out_min and e[k] < 0): it never grows deeper
 *     into a saturation it cannot act on, the output lands exactly on the limit, and the integral
 *     moves again at once when the error reverses;
 *  2. clamp: I[k] = clamp(I', out_min - f, out_max - f) with f = clamp(ff[k], out_min, out_max):
 *     the integral term alone never drives the output past a limit, so a reversed error leaves
 *     saturation within one step even after a long saturation or a feed-forward jump (f rather than
 *     ff so that a feed-forward beyond a limit does not force the integral to the opposite sign).
 *     u[k] = clamp(ff[k] + p[k] + I[k], out_min, out_max)
 * Bad input: dt_s <= 0 or not finite, or any input not finite -> u[k] = u[k-1] and nothing is
 * integrated. No NaN or infinity ever leaves the step. With out_min > out_max (invalid config,
 * see rw_pi_controller_config_is_valid) the output is held.
 * ki_per_s * dt_s is computed once per (ki_per_s, dt_s) and kept (the product the law uses first, so
 * the same value bit for bit); comparisons run on the bit patterns with the C semantics.
 */
float rw_pi_controller_step(rw_pi_controller *c, float setpoint, float measurement,
                            float feed_forward, float dt_s)
{
    const rw_pi_controller_config *cfg = &c->cfg;
    /* Only the limits are checked here (one comparison, false for NaN): a non-finite gain makes u
     * non-finite, which the check below catches. */
    if (!rw_f32_finite(setpoint) || !rw_f32_finite(measurement) || !rw_f32_finite(feed_forward) ||
        !rw_f32_positive_finite(dt_s) || !rw_f32_le(cfg->out_min, cfg->out_max)) {
        return c->state.output;
    }
    if (!rw_f32_same(cfg->ki_per_s, c->state.ki_dt_ki_per_s) || !rw_f32_same(dt_s, c->state.ki_dt_dt_s)) {
        c->state.ki_dt = cfg->ki_per_s * dt_s;
        c->state.ki_dt_ki_per_s = cfg->ki_per_s;
        c->state.ki_dt_dt_s = dt_s;
    }
    const float error = setpoint - measurement;
    const float p = cfg->kp * error;
    float integral = c->state.integral + c->state.ki_dt * error;
    const float ff_p = feed_forward + p; /* (ff + p) + I: the order C evaluates ff + p + I in */
    const float unsaturated = ff_p + integral;
    const float candidate = integral;
    if (rw_f32_gt(unsaturated, cfg->out_max) && rw_f32_positive(error)) {
        /* conditional integration: only up to the limit, never backwards */
        integral = maxf(c->state.integral, cfg->out_max - feed_forward - p);
    } else if (rw_f32_lt(unsaturated, cfg->out_min) && rw_f32_lt(error, 0.0f)) {
        integral = minf(c->state.integral, cfg->out_min - feed_forward - p);
    }
    const float ff_in_limits = clampf(feed_forward, cfg->out_min, cfg->out_max);
    integral = clampf(integral, cfg->out_min - ff_in_limits, cfg->out_max - ff_in_limits);
    /* the integral untouched by the anti-windup (the usual case): u is the sum already made */
    const float u = rw_f32_same(integral, candidate) ? unsaturated : ff_p + integral;
    if (!rw_f32_finite(integral) || !rw_f32_finite(u)) { /* overflow of huge (but finite) inputs */
        return c->state.output;
    }
    c->state.integral = integral;
    if (rw_f32_ge(u, cfg->out_max)) {
        c->state.output = cfg->out_max;
        c->state.saturation = 1;
    } else if (rw_f32_le(u, cfg->out_min)) {
        c->state.output = cfg->out_min;
        c->state.saturation = -1;
    } else {
        c->state.output = u;
        c->state.saturation = 0;
    }
    return c->state.output;
}
