/*
 * rw_pi_controller.c - PI controller with feed-forward and anti-windup, Q16.16 fixed point.
 */
#include "rw_pi_controller.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

/* kp is kept in Q24: gains up to this (throttle per m/s) */
#define RW_PI_MAX_KP 127.0f
/* ki_per_s dt_s is kept in Q32: up to this (integrating half the error per step is far beyond any loop) */
#define RW_PI_MAX_KI_DT 0.49f
/* the error saturates at +-this, Q16 (32768 error units): the products with the gains stay in 64 bits */
#define RW_PI_MAX_ERROR_Q16 INT32_MAX

void rw_pi_controller_init(rw_pi_controller *c, const rw_pi_controller_config *cfg)
{
    c->cfg = *cfg;
    rw_pi_controller_prepare(c, 0.0f);
    rw_pi_controller_reset(c);
}

void rw_pi_controller_config_defaults(rw_pi_controller_config *cfg)
{
    cfg->kp = RW_DEFAULT_SPEED_KP;
    cfg->ki_per_s = RW_DEFAULT_SPEED_KI_PER_S;
    cfg->out_min = RW_DEFAULT_SPEED_OUT_MIN;
    cfg->out_max = RW_DEFAULT_SPEED_OUT_MAX;
}

static int32_t clamp_q16(int64_t x, int32_t lo, int32_t hi)
{
    return x < lo ? lo : (x > hi ? hi : (int32_t)x);
}

void rw_pi_controller_reset(rw_pi_controller *c)
{
    c->state.integral_q32 = 0;
    c->state.saturation = 0;
    /* Keep the held output inside the limits when 0 is not (e.g. out_min = 0.1). */
    const int32_t lo = c->state.out_min_q16;
    const int32_t hi = c->state.out_max_q16;
    c->state.output_q16 = lo > 0 ? lo : (hi < 0 ? hi : 0);
}

int32_t rw_pi_controller_output_q16(const rw_pi_controller *c)
{
    return c->state.output_q16;
}

bool rw_pi_controller_config_is_valid(const rw_pi_controller_config *cfg)
{
    return rw_f32_finite(cfg->kp) && rw_f32_ge(cfg->kp, 0.0f) && rw_f32_finite(cfg->ki_per_s) &&
           rw_f32_ge(cfg->ki_per_s, 0.0f) && rw_f32_finite(cfg->out_min) && rw_f32_finite(cfg->out_max) &&
           rw_f32_le(cfg->out_min, cfg->out_max);
}

/* x scale for a non-negative config value, rounded, saturated at max scale (< 2^31); NaN -> 0 (float, once
 * per change; a float -> uint32 conversion: float -> int64 would link libgcc's double-precision code). */
static uint32_t gain_fixed(float x, float max, float scale)
{
    if (!rw_f32_positive(x)) {
        return 0u;
    }
    const float limited = rw_f32_lt(x, max) ? x : max;
    return (uint32_t)(limited * scale + 0.5f);
}

/* ki_per_s dt_s in Q32, saturated at RW_PI_MAX_KI_DT (dt_s finite and > 0). */
static int64_t ki_dt_q32_of(float ki_per_s, float dt_s)
{
    const float ki_dt = ki_per_s * dt_s;
    return (int64_t)gain_fixed(rw_f32_finite(ki_dt) ? ki_dt : RW_PI_MAX_KI_DT, RW_PI_MAX_KI_DT, 4294967296.0f);
}

void rw_pi_controller_prepare(rw_pi_controller *c, float dt_s)
{
    const rw_pi_controller_config *cfg = &c->cfg;
    c->state.valid = rw_pi_controller_config_is_valid(cfg);
    const bool usable = c->state.valid && rw_f32_positive_finite(dt_s);
    c->state.kp_q24 = c->state.valid ? (int32_t)gain_fixed(cfg->kp, RW_PI_MAX_KP, 16777216.0f) : 0;
    c->state.ki_dt_q32 = usable ? ki_dt_q32_of(cfg->ki_per_s, dt_s) : 0;
    c->state.prepared_dt_s = usable ? dt_s : 0.0f;
    c->state.out_min_q16 = c->state.valid ? rw_f32_to_q16(cfg->out_min) : 0;
    c->state.out_max_q16 = c->state.valid ? rw_f32_to_q16(cfg->out_max) : 0;
}

void rw_pi_controller_set_out_min_q16(rw_pi_controller *c, int32_t out_min_q16)
{
    c->state.out_min_q16 = out_min_q16 < c->state.out_max_q16 ? out_min_q16 : c->state.out_max_q16;
}

/*
 * Continuous law:   u(t) = ff(t) + kp * e(t) + ki * integral(e dt),   e = setpoint - measurement
 * Discrete law (forward-Euler integral, step k, dt = dt_s), all in fixed point:
 *     e[k]  = setpoint[k] - measurement[k]                              (Q16)
 *     p[k]  = kp * e[k]                                                  (Q16, rounded)
 *     I'    = I[k-1] + ki_per_s * dt * e[k]                              (Q32, candidate integral)
 *     v     = ff[k] + p[k] + I'                                          (unsaturated output)
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
 *     u[k] = clamp(ff[k] + p[k] + I[k], out_min, out_max)           (I[k] rounded to Q16)
 * Bad input: dt_s <= 0 or not finite, a non-finite config, or out_min > out_max (invalid config, see
 * rw_pi_controller_config_is_valid, as prepared) -> u[k] = u[k-1] and nothing is integrated. Sums run in 64 bits
 * with the error saturated at +-32768 units, kp at 127 and ki_per_s dt_s at 0.49: nothing overflows,
 * whatever the Q16 inputs.
 * kp, ki_per_s * dt_s and the limits are converted by rw_pi_controller_prepare, not here.
 */
int32_t rw_pi_controller_step(rw_pi_controller *c, int32_t setpoint_q16, int32_t measurement_q16,
                              int32_t feed_forward_q16, float dt_s)
{
    if (!c->state.valid || !rw_f32_positive_finite(dt_s)) {
        return c->state.output_q16;
    }
    const int64_t ki_dt_q32 =
        rw_f32_same(dt_s, c->state.prepared_dt_s) ? c->state.ki_dt_q32 : ki_dt_q32_of(c->cfg.ki_per_s, dt_s);
    const int32_t out_min = c->state.out_min_q16;
    const int32_t out_max = c->state.out_max_q16;
    const int64_t wide_error = (int64_t)setpoint_q16 - measurement_q16;
    const int32_t error = wide_error > RW_PI_MAX_ERROR_Q16
                              ? RW_PI_MAX_ERROR_Q16
                              : (wide_error < -RW_PI_MAX_ERROR_Q16 ? -RW_PI_MAX_ERROR_Q16 : (int32_t)wide_error);
    /* 32 x 32 -> 64-bit products inline (rw_mul_s32_s64): kp_q24 and ki_dt_q32 are under 2^31 */
    const int64_t p = (rw_mul_s32_s64(c->state.kp_q24, error) + (1 << 23)) >> 24; /* |p| < 2^38 */
    const int64_t ff = feed_forward_q16;
    int64_t integral = c->state.integral_q32 + (rw_mul_s32_s64((int32_t)ki_dt_q32, error) >> 16);
    const int64_t unsaturated = ff + p + ((integral + 32768) >> 16);
    if (unsaturated > out_max && error > 0) {
        /* conditional integration: only up to the limit, never backwards */
        const int64_t limit = (out_max - ff - p) * 65536;
        integral = c->state.integral_q32 > limit ? c->state.integral_q32 : limit;
    } else if (unsaturated < out_min && error < 0) {
        const int64_t limit = (out_min - ff - p) * 65536;
        integral = c->state.integral_q32 < limit ? c->state.integral_q32 : limit;
    }
    const int64_t ff_in_limits = clamp_q16(ff, out_min, out_max);
    const int64_t low = (out_min - ff_in_limits) * 65536;
    const int64_t high = (out_max - ff_in_limits) * 65536;
    integral = integral < low ? low : (integral > high ? high : integral);
    c->state.integral_q32 = integral;
    const int64_t u = ff + p + ((integral + 32768) >> 16);
    if (u >= out_max) {
        c->state.output_q16 = out_max;
        c->state.saturation = 1;
    } else if (u <= out_min) {
        c->state.output_q16 = out_min;
        c->state.saturation = -1;
    } else {
        c->state.output_q16 = (int32_t)u;
        c->state.saturation = 0;
    }
    return c->state.output_q16;
}

int32_t rw_pi_controller_integral_q16(const rw_pi_controller *c)
{
    const int64_t q16 = c->state.integral_q32 >> 16;
    return q16 > INT32_MAX ? INT32_MAX : (q16 < INT32_MIN ? INT32_MIN : (int32_t)q16);
}

float rw_pi_controller_integral(const rw_pi_controller *c)
{
    /* to Q16 (2^-16 of the output unit), then to float by bit operations (no 64-bit float conversion) */
    return rw_f32_from_q16(rw_pi_controller_integral_q16(c));
}
