/*
 * rw_mt_speed_estimator.c - M/T speed estimator.
 */
#include "rw_mt_speed_estimator.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

#include <stdint.h>

#define RW_TWO_PI_F 6.28318530718f
#define RW_US_PER_S_F 1.0e6f
#define RW_HALF_RANGE_U32 0x80000000u
/* Integer M/T division range: dn 1e6 < 2^30 and counts_per_rev dT < 2^24 (the remainder shifted by 8
 * stays within 32 bits). */
#define RW_MT_INT_MAX_DN 1073u
#define RW_MT_INT_MAX_DEN 0x00FFFFFFu
/* 1e6 x 65536: one edge per microsecond-revolution, in Q16 */
#define RW_MT_US_PER_S_Q16 65536000000ull

/* The quotient is developed to at least this many significant bits (1.2e-4 relative; the 1 us timestamps
 * resolve a 2 ms interval to 5e-4) or to all 16 fraction bits of Q16.16, whichever comes first. */
#define RW_MT_QUOTIENT_MIN_Q 0x2000u

/* The M/T quotient dn 1e6 / (counts_per_rev dT) in rev/s, Q16.16, by 32-bit integer long division (the
 * M0+ has no divider: libgcc divides bit by bit, ~4 instructions a quotient bit): the numerator scaled up
 * as far as 32 bits allow gives the integer part and the first fraction bits in one division, 8-bit digits
 * follow only while fewer than 14 significant bits are known; rounded to nearest at the last bit developed
 * (one division at the usual few edges per tick). false when an operand is too large for that (the caller
 * then divides in float, a rare path: several edges over a quarter second). Saturates at 32768 rev/s. */
static bool mt_rev_per_s_q16(uint32_t dn, uint32_t counts_per_rev, uint32_t dt_us, uint32_t max_dt_us, int32_t *out)
{
    if (dn > RW_MT_INT_MAX_DN || dt_us > max_dt_us) { /* max_dt_us = RW_MT_INT_MAX_DEN / counts_per_rev */
        return false;
    }
    const uint32_t den = counts_per_rev * dt_us; /* < 2^24 */
    uint32_t scaled = dn * 1000000u;            /* < 2^30 */
    uint32_t shift = 0u;
    while (shift < 16u && scaled < 0x40000000u) { /* dn >= 1: at most 10 steps */
        scaled <<= 1;
        ++shift;
    }
    uint32_t q = scaled / den;
    uint32_t rest = 16u - shift; /* fraction bits not developed yet */
    if (q >= (0x80000000u >> rest)) {
        *out = INT32_MAX; /* >= 32768 rev/s */
        return true;
    }
    uint32_t r = scaled - q * den;
    while (rest > 0u && q < RW_MT_QUOTIENT_MIN_Q) { /* r < den < 2^24: r << 8 fits */
        const uint32_t bits = rest > 8u ? 8u : rest;
        const uint32_t shifted = r << bits;
        const uint32_t digit = shifted / den;
        q = (q << bits) | digit;
        r = shifted - digit * den;
        rest -= bits;
    }
    q = (q + (2u * r >= den ? 1u : 0u)) << rest;
    *out = q > (uint32_t)INT32_MAX ? INT32_MAX : (int32_t)q;
    return true;
}

/* 2 pi r in metres, Q32 (radii up to 0.68 m; float arithmetic, once per radius). */
static uint32_t two_pi_r_q32(float r_m)
{
    const float x = RW_TWO_PI_F * r_m * 4294967296.0f;
    return rw_f32_lt(x, 4294967040.0f) ? (uint32_t)x : 0xFFFFFF00u;
}

/* The filtered rope speed, m/s Q16.16: 2 pi r x the filtered rev/s, rounded; 0 for an invalid radius. */
static int32_t rope_q16_of(const rw_mt_speed_estimator *e)
{
    const uint32_t k = e->state.two_pi_r_q32;
    const int32_t rev_q16 = rw_lowpass_output_q16(&e->state.filter);
    if (rev_q16 <= 0) {
        return 0;
    }
    const uint64_t rope_q48 = rw_mul_u32_u64((uint32_t)rev_q16, k) + 0x80000000u;
    const uint64_t rope_q16 = rope_q48 >> 32;
    return rope_q16 > (uint64_t)INT32_MAX ? INT32_MAX : (int32_t)rope_q16;
}

void rw_mt_speed_estimator_init(rw_mt_speed_estimator *e, const rw_mt_speed_estimator_config *cfg)
{
    e->cfg = *cfg;
    const rw_lowpass_config filter_cfg = {.tau_s = cfg->filter_tau_s};
    rw_lowpass_init(&e->state.filter, &filter_cfg);
    rw_mt_speed_estimator_prepare(e, 0.0f);
    rw_mt_speed_estimator_reset(e);
}

void rw_mt_speed_estimator_prepare(rw_mt_speed_estimator *e, float dt_s)
{
    e->state.valid = rw_mt_speed_estimator_config_is_valid(&e->cfg);
    const float r_m = e->cfg.wheel_radius_m;
    e->state.two_pi_r_q32 = rw_f32_positive_finite(r_m) ? two_pi_r_q32(r_m) : 0u;
    /* the integer quotient's range in edge time, divided out once here (not on every step) */
    e->state.max_int_dt_us = e->cfg.counts_per_rev > 0u ? RW_MT_INT_MAX_DEN / e->cfg.counts_per_rev : 0u;
    e->state.filter.cfg.tau_s = e->cfg.filter_tau_s;
    rw_lowpass_prepare(&e->state.filter, dt_s);
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
    e->state.raw_rev_per_s_q16 = 0;
    rw_lowpass_reset(&e->state.filter);
    e->state.rope_mps_q16 = 0;
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
    return rw_f32_from_q16(rw_lowpass_output_q16(&e->state.filter));
}

float rw_mt_speed_estimator_rpm(const rw_mt_speed_estimator *e)
{
    return 60.0f * rw_mt_speed_estimator_rev_per_s(e);
}

int32_t rw_mt_speed_estimator_rope_mps_q16(const rw_mt_speed_estimator *e)
{
    return e->state.rope_mps_q16;
}

float rw_mt_speed_estimator_rope_mps(const rw_mt_speed_estimator *e)
{
    return rw_f32_from_q16(e->state.rope_mps_q16);
}

float rw_mt_speed_estimator_raw_rev_per_s(const rw_mt_speed_estimator *e)
{
    return rw_f32_from_q16(e->state.raw_rev_per_s_q16);
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
 * All in integers: n and y in rev/s Q16.16 (n by 32-bit long division, to 14 significant bits at least; y kept to
 * 2^-32 by rw_lowpass), the silence bound compared exactly in 64 bits, 2 pi r in metres Q32, the rope
 * speed rounded to Q16.16 (15 um/s).
 * Inconsistent input (dn >= 2^31 i.e. the count went backwards, dT == 0 with edges, now_us before
 * the last edge, invalid config) changes nothing except that a backward count re-latches the
 * reference. No NaN or infinity ever leaves the step (the float outputs are conversions of Q16.16 values).
 */
float rw_mt_speed_estimator_step(rw_mt_speed_estimator *e, uint32_t count, uint32_t edge_us,
                                 uint32_t now_us, float dt_s)
{
    if (!e->state.valid) {
        e->state.rope_mps_q16 = 0;
        return 0.0f;
    }
    if (!e->state.primed) {
        e->state.last_count = count;
        e->state.last_edge_us = edge_us;
        e->state.primed = true;
        e->state.rope_mps_q16 = rope_q16_of(e);
        return rw_f32_from_q16(e->state.rope_mps_q16);
    }

    const uint32_t dn = count - e->state.last_count;
    int32_t n_q16 = e->state.raw_rev_per_s_q16;

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
            e->state.raw_rev_per_s_q16 = 0;
            e->state.stale = true;
            rw_lowpass_reset(&e->state.filter);
            e->state.rope_mps_q16 = 0;
            return 0.0f;
        }
        if (dt_edges_us > 0u) {
            if (!mt_rev_per_s_q16(dn, e->cfg.counts_per_rev, dt_edges_us, e->state.max_int_dt_us, &n_q16)) {
                /* rare: several edges over more than 2^24 / counts_per_rev us */
                n_q16 = rw_f32_to_q16(((float)dn * RW_US_PER_S_F) /
                                      ((float)e->cfg.counts_per_rev * (float)dt_edges_us));
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
                e->state.raw_rev_per_s_q16 = 0;
                e->state.stale = true;
                rw_lowpass_reset(&e->state.filter);
                e->state.rope_mps_q16 = 0;
                return 0.0f;
            }
            if (silence_us > 0u && n_q16 > 0) {
                /* n <= 1e6 / (counts_per_rev s): compared exactly as n span <= 1e6 (Q16, 64 bits); the
                 * bound is divided out only when the estimate exceeds it */
                const uint64_t span = (uint64_t)e->cfg.counts_per_rev * silence_us;
                if ((uint64_t)(uint32_t)n_q16 * span > RW_MT_US_PER_S_Q16) {
                    n_q16 = (int32_t)(RW_MT_US_PER_S_Q16 / span); /* < n_q16 */
                }
            }
        }
    }

    e->state.raw_rev_per_s_q16 = n_q16;
    rw_lowpass_step(&e->state.filter, n_q16, dt_s);
    e->state.rope_mps_q16 = rope_q16_of(e);
    return rw_f32_from_q16(e->state.rope_mps_q16);
}
