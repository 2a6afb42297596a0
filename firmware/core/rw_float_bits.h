/*
 * rw_float_bits.h - single-precision tests and comparisons on the IEEE-754 bit pattern.
 *
 * The Cortex-M0+ has no FPU: every float comparison is a libgcc call (__gtsf2, __ltsf2, ... about 40-50
 * instructions with the call) and isfinite() is two of them. These inline helpers give exactly the
 * same answers as the C operators (NaN compares false, -0 == +0, infinities ordered) in a few integer
 * instructions. Bit-pattern equality (rw_f32_same) is what the controllers use to know whether a
 * precomputed constant still belongs to the current configuration and dt.
 * Also the fixed-point helpers of the tick path: Q16.16 conversions from and to float on the bit pattern,
 * and a 32 x 32 -> 64-bit multiply without the libgcc call.
 * Portable core header: no Arduino header, no heap.
 */
#ifndef RW_FLOAT_BITS_H
#define RW_FLOAT_BITS_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* Always inlined: each is a handful of instructions, a call would double it (gcc -Os keeps calls). */
#if defined(__GNUC__)
#define RW_F32_INLINE static inline __attribute__((always_inline))
#else
#define RW_F32_INLINE static inline
#endif

#define RW_F32_EXP_MASK 0x7F800000u
#define RW_F32_ABS_MASK 0x7FFFFFFFu

RW_F32_INLINE uint32_t rw_f32_bits(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

/* isfinite(x): the exponent is not all ones. */
RW_F32_INLINE bool rw_f32_finite(float x)
{
    return (rw_f32_bits(x) & RW_F32_EXP_MASK) != RW_F32_EXP_MASK;
}

RW_F32_INLINE bool rw_f32_isnan(float x)
{
    return (rw_f32_bits(x) & RW_F32_ABS_MASK) > RW_F32_EXP_MASK;
}

/* x > 0.0f (true for +inf, false for NaN and both zeros). */
RW_F32_INLINE bool rw_f32_positive(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return bits != 0u && bits <= RW_F32_EXP_MASK;
}

/* x > 0.0f and finite. */
RW_F32_INLINE bool rw_f32_positive_finite(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return bits != 0u && bits < RW_F32_EXP_MASK;
}

/* Monotonic integer key of a non-NaN float: a < b exactly when key(a) < key(b); key(-0) == key(+0). */
RW_F32_INLINE int32_t rw_f32_key(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return (bits & 0x80000000u) != 0u ? -(int32_t)(bits & RW_F32_ABS_MASK) : (int32_t)bits;
}

/* a < b, a <= b, a > b, a >= b with the C semantics (false when either is NaN). */
RW_F32_INLINE bool rw_f32_lt(float a, float b)
{
    return !rw_f32_isnan(a) && !rw_f32_isnan(b) && rw_f32_key(a) < rw_f32_key(b);
}

RW_F32_INLINE bool rw_f32_le(float a, float b)
{
    return !rw_f32_isnan(a) && !rw_f32_isnan(b) && rw_f32_key(a) <= rw_f32_key(b);
}

RW_F32_INLINE bool rw_f32_gt(float a, float b)
{
    return rw_f32_lt(b, a);
}

RW_F32_INLINE bool rw_f32_ge(float a, float b)
{
    return rw_f32_le(b, a);
}

/* The same bit pattern (used for "is this cached constant still valid": stricter than ==). */
RW_F32_INLINE bool rw_f32_same(float a, float b)
{
    return rw_f32_bits(a) == rw_f32_bits(b);
}

/* floor(x + 0.5) for 0 <= x < 2^24 from the bit pattern (round half up of the exact value; x < 0.5 and
 * NaN-free non-positive x give 0). The caller guarantees the range; no soft-float call. */
RW_F32_INLINE uint32_t rw_f32_round_half_up_u24(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    const int32_t exp2 = (int32_t)(bits >> 23) - 127; /* x = m 2^(exp2 - 23) */
    if ((bits & 0x80000000u) != 0u || exp2 < -1) {
        return 0u;
    }
    const uint32_t mantissa = (bits & 0x007FFFFFu) | 0x00800000u;
    const uint32_t shift = (uint32_t)(23 - exp2); /* 0..24 for x < 2^24 */
    return shift == 0u ? mantissa : (mantissa + (1u << (shift - 1u))) >> shift;
}

/* The float product |x| k_odd 2^k_shift (k_odd odd, < 128), rounded to nearest even exactly as the float
 * multiplication rounds it, returned as significand 2^(*exp2) with the significand in [2^23, 2^24] (0 for
 * a zero or subnormal x, whose product lies far below any unit converted to). x finite; the product may
 * exceed FLT_MAX where the float multiply would give infinity (callers saturate long before). Costs a
 * 32-bit multiply and a few shifts instead of __aeabi_fmul. */
RW_F32_INLINE uint32_t rw_f32_mul_small(float x, uint32_t k_odd, int32_t k_shift, int32_t *exp2)
{
    const uint32_t bits = rw_f32_bits(x);
    const uint32_t biased = (bits >> 23) & 0xFFu;
    if (biased == 0u) {
        *exp2 = 0;
        return 0u;
    }
    uint32_t p = ((bits & 0x007FFFFFu) | 0x00800000u) * k_odd; /* < 2^31 */
    int32_t e = (int32_t)biased - 150 + k_shift;                 /* |x| = m 2^(biased - 150) */
    uint32_t top = p >> 24; /* < 128: the bits beyond a 24-bit significand, found in three steps */
    uint32_t drop = 0u;
    if (top >= 16u) {
        top >>= 4;
        drop = 4u;
    }
    if (top >= 4u) {
        top >>= 2;
        drop += 2u;
    }
    if (top >= 2u) {
        top >>= 1;
        drop += 1u;
    }
    drop += top; /* top is 0 or 1 here */
    if (drop > 0u) {
        const uint32_t rem = p & ((1u << drop) - 1u);
        const uint32_t half = 1u << (drop - 1u);
        p >>= drop;
        if (rem > half || (rem == half && (p & 1u) != 0u)) {
            ++p; /* may reach 2^24: still exact */
        }
        e += (int32_t)drop;
    }
    *exp2 = e;
    return p;
}

/* (float)elapsed_ms > threshold_s * 1000.0f (or_equal: >=), the answer of that float expression without
 * a soft-float call: the product is rounded as the float multiply rounds it (rw_f32_mul_small) and compared
 * with the integer exactly. NaN gives false, a negative threshold true, +inf false. Thresholds of 2^24 ms
 * (4.6 hours) and more fall back to the float expression. */
RW_F32_INLINE bool rw_f32_ms_past(uint32_t elapsed_ms, float threshold_s, bool or_equal)
{
    const uint32_t bits = rw_f32_bits(threshold_s);
    const uint32_t biased = bits >> 23; /* sign bit included: negative thresholds fail the next test */
    if (biased >= 118u && biased < 149u && elapsed_ms < (1u << (biased - 118u))) {
        /* the usual case, decided in a few instructions: threshold_s >= 2^(biased - 127), so the product is
         * over 2^(biased - 127) 512 = 2^(biased - 118) > elapsed_ms */
        return false;
    }
    if (rw_f32_isnan(threshold_s)) {
        return false;
    }
    if ((bits & RW_F32_ABS_MASK) == 0u) { /* +-0 */
        return or_equal || elapsed_ms > 0u;
    }
    if ((bits & 0x80000000u) != 0u) { /* negative, -inf included */
        return true;
    }
    if (!rw_f32_finite(threshold_s)) {
        return false;
    }
    int32_t exp2;
    const uint32_t p = rw_f32_mul_small(threshold_s, 125u, 3, &exp2); /* threshold_s 1000 = p 2^exp2 */
    if (p == 0u) { /* subnormal threshold: 0 < product < 1 */
        return elapsed_ms > 0u;
    }
    if (exp2 > 0 || (exp2 == 0 && p >= 0x01000000u)) { /* >= 2^24 ms: (float)elapsed_ms may round */
        const float elapsed = (float)elapsed_ms;
        const float limit = threshold_s * 1000.0f;
        return or_equal ? elapsed >= limit : elapsed > limit;
    }
    /* product < 2^24 <= (float)elapsed_ms whenever elapsed_ms >= 2^24, so the integer compare is exact */
    const uint32_t shift = (uint32_t)-exp2;
    const uint32_t whole = shift >= 32u ? 0u : p >> shift;
    const bool fraction = shift >= 32u ? true : (p & ((1u << shift) - 1u)) != 0u;
    return (or_equal && !fraction) ? elapsed_ms >= whole : elapsed_ms > whole;
}

/* Q16.16 fixed point: x 65536 in an int32 (resolution 1.5e-5, range +-32768). */
#define RW_Q16_ONE 65536
#define RW_Q16_MAX INT32_MAX

/* round(x 2^frac_bits) to nearest (halves away from zero), saturated to +-INT32_MAX; NaN -> 0 (frac_bits
 * 0..31). Bit operations only (no soft-float call). */
RW_F32_INLINE int32_t rw_f32_to_fixed(float x, uint32_t frac_bits)
{
    const uint32_t bits = rw_f32_bits(x);
    const uint32_t biased = (bits >> 23) & 0xFFu;
    if (biased == 0xFFu && (bits & 0x007FFFFFu) != 0u) {
        return 0; /* NaN */
    }
    if (biased + frac_bits < 125u) {
        return 0; /* |x| 2^frac_bits < 1/4: rounds to 0 (subnormals and zeros too) */
    }
    uint32_t magnitude;
    if (biased + frac_bits >= 158u) {
        magnitude = (uint32_t)INT32_MAX; /* |x| 2^frac_bits >= 2^31 (infinities too) */
    } else {
        const uint32_t mantissa = (bits & 0x007FFFFFu) | 0x00800000u; /* |x| = mantissa 2^(biased - 150) */
        const int32_t shift = (int32_t)(biased + frac_bits) - 150;    /* x 2^frac_bits = mantissa 2^shift */
        if (shift >= 0) {
            magnitude = mantissa << (uint32_t)shift; /* < 2^31 */
        } else {
            const uint32_t right = (uint32_t)-shift; /* 1..25 */
            magnitude = (mantissa + (1u << (right - 1u))) >> right;
        }
    }
    return (bits & 0x80000000u) != 0u ? -(int32_t)magnitude : (int32_t)magnitude;
}

/* round(x 65536) to nearest (halves away from zero), saturated to +-INT32_MAX; NaN -> 0: Q16.16. */
RW_F32_INLINE int32_t rw_f32_to_q16(float x)
{
    return rw_f32_to_fixed(x, 16u);
}

/* q / 65536 as a float, rounded to nearest even as a conversion rounds (exact for |q| < 2^24). Bit
 * operations only. */
RW_F32_INLINE float rw_f32_from_q16(int32_t q)
{
    if (q == 0) {
        return 0.0f;
    }
    const uint32_t sign = q < 0 ? 0x80000000u : 0u;
    uint32_t m = q < 0 ? 0u - (uint32_t)q : (uint32_t)q;
    uint32_t top = 31u; /* the highest set bit of m, found in five steps */
    if ((m >> 16) == 0u) {
        m <<= 16;
        top -= 16u;
    }
    if ((m >> 24) == 0u) {
        m <<= 8;
        top -= 8u;
    }
    if ((m >> 28) == 0u) {
        m <<= 4;
        top -= 4u;
    }
    if ((m >> 30) == 0u) {
        m <<= 2;
        top -= 2u;
    }
    if ((m >> 31) == 0u) {
        m <<= 1;
        top -= 1u;
    }
    /* m normalised: bit 31 set; keep 24 bits, round the 8 below to nearest even */
    uint32_t mantissa = m >> 8;
    const uint32_t rest = m & 0xFFu;
    if (rest > 0x80u || (rest == 0x80u && (mantissa & 1u) != 0u)) {
        ++mantissa;
        if (mantissa == 0x01000000u) {
            mantissa >>= 1;
            ++top;
        }
    }
    const uint32_t bits = sign | ((top - 16u + 127u) << 23) | (mantissa & 0x007FFFFFu);
    float x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

/* a b as a 64-bit product of two 32-bit unsigned values, inline: the Cortex-M0+ multiplies 32 x 32 -> 32 bits
 * in one cycle but has no long multiply, and gcc calls __aeabi_lmul (a 64 x 64 product, ~40 instructions
 * with the call) for (uint64_t)a * b. Four 16 x 16 products instead. */
RW_F32_INLINE uint64_t rw_mul_u32_u64(uint32_t a, uint32_t b)
{
    const uint32_t a_lo = a & 0xFFFFu;
    const uint32_t a_hi = a >> 16;
    const uint32_t b_lo = b & 0xFFFFu;
    const uint32_t b_hi = b >> 16;
    const uint32_t lo = a_lo * b_lo;
    const uint32_t mid_a = a_hi * b_lo;
    const uint32_t mid_b = a_lo * b_hi;
    const uint32_t hi = a_hi * b_hi;
    const uint32_t mid = mid_a + (lo >> 16) + (mid_b & 0xFFFFu); /* < 2^32: no carry lost */
    const uint32_t low_word = (mid << 16) | (lo & 0xFFFFu);
    const uint32_t high_word = hi + (mid >> 16) + (mid_b >> 16);
    return ((uint64_t)high_word << 32) | low_word;
}

/* a b for signed 32-bit values, as a 64-bit product (see rw_mul_u32_u64). */
RW_F32_INLINE int64_t rw_mul_s32_s64(int32_t a, int32_t b)
{
    const uint32_t ma = a < 0 ? 0u - (uint32_t)a : (uint32_t)a;
    const uint32_t mb = b < 0 ? 0u - (uint32_t)b : (uint32_t)b;
    const uint64_t m = rw_mul_u32_u64(ma, mb);
    return (a < 0) != (b < 0) ? -(int64_t)m : (int64_t)m;
}

#endif /* RW_FLOAT_BITS_H */
