/*
 * rw_mt_speed_estimator.c - M/T speed estimator.
 */
#include "rw_mt_speed_estimator.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

#include <stdint.h>
#include <string.h>

#define RW_TWO_PI_F 6.28318530718f
#define RW_US_PER_S_F 1.0e6f
#define RW_HALF_RANGE_U32 0x80000000u
#define RW_BOUND_SURE_UNDER_F 0.999e6f
/* Integer M/T division range: dn 1e6 < 2^30 and counts_per_rev dT < 2^24 (float-exact operands). */
#define RW_MT_INT_MAX_DN 1073u
#define RW_MT_INT_MAX_DEN 0x00FFFFFFu

/* The M/T quotient dn 1e6 / (counts_per_rev dT) in rev/s by integer long division: the M0+ divides
 * 32-bit integers in ~40 instructions and floats in ~350. The quotient is developed to at least 26
 * bits, the remainder folded into its last bit (sticky), converted once (one rounding) and scaled by a
 * power of two on the exponent (exact): the correctly rounded quotient, the same bits as the float
 * division of these exactly representable operands. false when an operand is too large for that (the
 * caller then divides in float). */
static bool mt_rev_per_s_int(uint32_t dn, uint32_t counts_per_rev, uint32_t dt_us, float *out)
{
    if (dn > RW_MT_INT_MAX_DN || dt_us > RW_MT_INT_MAX_DEN / counts_per_rev) {
        return false;
    }
    const uint32_t num = dn * 1000000u; /* < 2^30, exact as a float too (dn 15625 < 2^24) */
    const uint32_t den = counts_per_rev * dt_us; /* < 2^24 */
    uint32_t q = num / den;
    uint32_t r = num - q * den;
    uint32_t frac_bits = 0u;
    while (q < 0x02000000u) { /* q < 2^25 and r < 2^24: both shift by 7 within 32 bits; <= 5 steps */
        const uint32_t shifted = r << 7;
        const uint32_t digit = shifted / den;
        q = (q << 7) | digit;
        r = shifted - digit * den;
        frac_bits += 7u;
    }
    q |= r != 0u ? 1u : 0u; /* q >= 2^25: bit 0 lies below the rounding bit of a 24-bit significand */
    float value = (float)q;
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    bits -= frac_bits << 23; /* / 2^frac_bits: the result stays a normal number */
    memcpy(out, &bits, sizeof bits);
    return true;
}

void rw_mt_speed_estimator_init(rw_mt_speed_estimator *e, const rw_mt_speed_estimator_config *cfg)
{
    e->cfg = *cfg;
    e->state.two_pi_r_m = 0.0f;
    e->state.two_pi_r_radius_m = 0.0f;
    const rw_lowpass_config filter_cfg = {.tau_s = cfg->filter_tau_s};
    rw_lowpass_init(&e->state.filter, &filter_cfg);
    rw_mt_speed_estimator_reset(e);
}

void rw_mt_speed_estimator_config_defaults(rw_mt_speed_estimator_config *cfg)
{
    cfg->counts_per_rev = RW_DEFAULT_ENCODER_COUNTS_PER_REV;
    cfg->timeout_us = RW_DEFAULT_SPEED_TIMEOUT_US;
    cfg->wheel_radius_m = RW_DEFAULT_WHEEL_RADIUS_M;
    cfg->filter_tau_s = RW_DEFAULT_SPEED_FILTER_TAU_S;
}

void rw_mt_speed_estimator_reset(rw_mt_speed_estimator *e)
{
    e->state.last_count = 0u;
    e->state.last_edge_us = 0u;
    e->state.raw_rev_per_s = 0.0f;
    rw_lowpass_reset(&e->state.filter);
    e->state.primed = false;
    e->state.stale = true;
}

bool rw_mt_speed_estimator_config_is_valid(const rw_mt_speed_estimator_config *cfg)
{
    return cfg->counts_per_rev > 0u && cfg->timeout_us > 0u && rw_f32_positive_finite(cfg->wheel_radius_m) &&
           rw_f32_finite(cfg->filter_tau_s) && rw_f32_ge(cfg->filter_tau_s, 0.0f);
}

float rw_mt_speed_estimator_rev_per_s(const rw_mt_speed_estimator *e)
{
    return rw_lowpass_output(&e->state.filter);
}

float rw_mt_speed_estimator_rpm(const rw_mt_speed_estimator *e)
{
    return 60.0f * rw_lowpass_output(&e->state.filter);
}

float rw_mt_speed_estimator_rope_mps(const rw_mt_speed_estimator *e)
{
    const float r_m = e->cfg.wheel_radius_m;
    if (!rw_f32_positive_finite(r_m)) {
        return 0.0f;
    }
    /* (2 pi r) y: the product kept by the step when it belongs to this radius (same bits either way) */
    const float two_pi_r_m = rw_f32_same(r_m, e->state.two_pi_r_radius_m) ? e->state.two_pi_r_m : RW_TWO_PI_F * r_m;
    return two_pi_r_m * rw_lowpass_output(&e->state.filter);
}

float rw_mt_speed_estimator_raw_rev_per_s(const rw_mt_speed_estimator *e)
{
    return e->state.raw_rev_per_s;
}

bool rw_mt_speed_estimator_is_stale(const rw_mt_speed_estimator *e)
{
    return e->state.stale;
}

/*
 * Discrete law (step k; all differences are uint32_t, i.e. modulo 2^32, so wrapping is harmless):
 *   first step after reset: latch (count, edge_us) as the reference; speed 0, stale.
 *   dn = count - last_count                      edges since the reference edge
 *   dT = edge_us - last_edge_us                  exact time between those edges, microseconds
 *   M/T, edges arrived (dn > 0, 0 < dT):
 *       n[k] = dn / counts_per_rev / (dT * 1e-6)           rev/s; reference := (count, edge_us)
 *     The measurement spans whole edge intervals, so it is exact at constant speed whatever the
 *     tick phase: no +-1 count quantisation as in plain M (count per tick), no tick-long period
 *     error as in plain T.
 *   No edge since the reference (dn == 0): silence s = now_us - last_edge_us. The edge interval in
 *     progress is already longer than s, so the speed cannot exceed the bound
 *       n_max = 1 / (counts_per_rev * s * 1e-6),      n[k] = min(n[k-1], n_max)
 *     (the estimate decays as 1/s when the wheel stops, rather than holding the last value).
 *   s > timeout_us: n[k] = 0, the filter is reset to 0 and the estimate is flagged stale.
 *   Edges arrived but dT > timeout_us (first edge after a stop): n[k] = 0, stale, the reference
 *     is re-latched; the speed is measured from the next edge on. Stale is cleared only by a
 *     measured interval (dn > 0, 0 < dT <= timeout_us).
 *   Filter: y[k] = rw_lowpass(n[k], dt_s) (pass-through when filter_tau_s == 0).
 *   Outputs: rev/s = y, rpm = 60 y, rope m/s = 2 pi wheel_radius_m y.
 * Inconsistent input (dn >= 2^31 i.e. the count went backwards, dT == 0 with edges, now_us before
 * the last edge, invalid config) changes nothing except that a backward count re-latches the
 * reference. No NaN or infinity ever leaves the step.
 */
float rw_mt_speed_estimator_step(rw_mt_speed_estimator *e, uint32_t count, uint32_t edge_us,
                                 uint32_t now_us, float dt_s)
{
    if (!rw_mt_speed_estimator_config_is_valid(&e->cfg)) {
        return 0.0f;
    }
    if (!e->state.primed) {
        e->state.last_count = count;
        e->state.last_edge_us = edge_us;
        e->state.primed = true;
        return rw_mt_speed_estimator_rope_mps(e);
    }

    e->state.filter.cfg.tau_s = e->cfg.filter_tau_s; /* cfg is public: follow a changed tau */
    if (!rw_f32_same(e->cfg.wheel_radius_m, e->state.two_pi_r_radius_m)) {
        e->state.two_pi_r_m = RW_TWO_PI_F * e->cfg.wheel_radius_m;
        e->state.two_pi_r_radius_m = e->cfg.wheel_radius_m;
    }
    const float counts_per_rev = (float)e->cfg.counts_per_rev;
    const uint32_t dn = count - e->state.last_count;
    float n_rev_per_s = e->state.raw_rev_per_s;

    if (dn >= RW_HALF_RANGE_U32) {
        /* Count went backwards (glitch or restarted capture): re-latch, keep the estimate. */
        e->state.last_count = count;
        e->state.last_edge_us = edge_us;
    } else if (dn > 0u) {
        const uint32_t dt_edges_us = edge_us - e->state.last_edge_us;
        if (dt_edges_us > e->cfg.timeout_us && (dn == 1u || dt_edges_us >= RW_HALF_RANGE_U32)) {
            /* First edge after a silence longer than the timeout (possibly longer than 2^31 us): no
             * speed can be measured across it. Re-latch; the next edge measures. Several edges over a
             * long interval (the caller missed ticks while the wheel turned) do measure: the mean. */
            e->state.last_count = count;
            e->state.last_edge_us = edge_us;
            e->state.raw_rev_per_s = 0.0f;
            e->state.stale = true;
            rw_lowpass_reset(&e->state.filter);
            return 0.0f;
        }
        if (dt_edges_us > 0u) {
            if (!mt_rev_per_s_int(dn, e->cfg.counts_per_rev, dt_edges_us, &n_rev_per_s)) {
                n_rev_per_s = ((float)dn * RW_US_PER_S_F) / (counts_per_rev * (float)dt_edges_us);
            }
            e->state.last_count = count;
            e->state.last_edge_us = edge_us;
            e->state.stale = false;
        }
        /* else: count moved, timestamp did not (not latched together); wait for a consistent pair. */
    } else {
        const uint32_t silence_us = now_us - e->state.last_edge_us;
        if (silence_us < RW_HALF_RANGE_U32) { /* now_us not before the last edge */
            if (silence_us > e->cfg.timeout_us) {
                e->state.raw_rev_per_s = 0.0f;
                e->state.stale = true;
                rw_lowpass_reset(&e->state.filter);
                return 0.0f;
            }
            if (silence_us > 0u) {
                /* n <= bound whenever n (counts_per_rev s) stays clearly under 1e6 (0.1 % margin, far
                 * above the rounding of either side): then the division is skipped, the result is the
                 * same. Otherwise the bound is computed as the law says. */
                const float span = counts_per_rev * (float)silence_us;
                if (!rw_f32_lt(n_rev_per_s * span, RW_BOUND_SURE_UNDER_F)) {
                    const float bound_rev_per_s = RW_US_PER_S_F / span;
                    if (rw_f32_gt(n_rev_per_s, bound_rev_per_s)) {
                        n_rev_per_s = bound_rev_per_s;
                    }
                }
            }
        }
    }

    if (!rw_f32_finite(n_rev_per_s) || rw_f32_lt(n_rev_per_s, 0.0f)) {
        n_rev_per_s = e->state.raw_rev_per_s;
    }
    e->state.raw_rev_per_s = n_rev_per_s;
    rw_lowpass_step(&e->state.filter, n_rev_per_s, dt_s);
    return rw_mt_speed_estimator_rope_mps(e);
}
