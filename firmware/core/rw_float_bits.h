/*
 * rw_float_bits.h - single-precision tests and comparisons on the IEEE-754 bit pattern.
 *
 * The Cortex-M0+ has no FPU: every float comparison is a libgcc call (__gtsf2, __ltsf2, ... about 40-50
 * instructions with the call) and isfinite() is two of them. These inline helpers give exactly the
 * same answers as the C operators (NaN compares false, -0 == +0, infinities ordered) in a few integer
 * instructions. Bit-pattern equality (rw_f32_same) is what the controllers use to know whether a
 * precomputed constant still belongs to the current configuration and dt.
 * Portable core header: no Arduino header, no heap.
 */
#ifndef RW_FLOAT_BITS_H
#define RW_FLOAT_BITS_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#define RW_F32_EXP_MASK 0x7F800000u
#define RW_F32_ABS_MASK 0x7FFFFFFFu

static inline uint32_t rw_f32_bits(float x)
{
    uint32_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

/* isfinite(x): the exponent is not all ones. */
static inline bool rw_f32_finite(float x)
{
    return (rw_f32_bits(x) & RW_F32_EXP_MASK) != RW_F32_EXP_MASK;
}

static inline bool rw_f32_isnan(float x)
{
    return (rw_f32_bits(x) & RW_F32_ABS_MASK) > RW_F32_EXP_MASK;
}

/* x > 0.0f (true for +inf, false for NaN and both zeros). */
static inline bool rw_f32_positive(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return bits != 0u && bits <= RW_F32_EXP_MASK;
}

/* x > 0.0f and finite. */
static inline bool rw_f32_positive_finite(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return bits != 0u && bits < RW_F32_EXP_MASK;
}

/* Monotonic integer key of a non-NaN float: a < b exactly when key(a) < key(b); key(-0) == key(+0). */
static inline int32_t rw_f32_key(float x)
{
    const uint32_t bits = rw_f32_bits(x);
    return (bits & 0x80000000u) != 0u ? -(int32_t)(bits & RW_F32_ABS_MASK) : (int32_t)bits;
}

/* a < b, a <= b, a > b, a >= b with the C semantics (false when either is NaN). */
static inline bool rw_f32_lt(float a, float b)
{
    return !rw_f32_isnan(a) && !rw_f32_isnan(b) && rw_f32_key(a) < rw_f32_key(b);
}

static inline bool rw_f32_le(float a, float b)
{
    return !rw_f32_isnan(a) && !rw_f32_isnan(b) && rw_f32_key(a) <= rw_f32_key(b);
}

static inline bool rw_f32_gt(float a, float b)
{
    return rw_f32_lt(b, a);
}

static inline bool rw_f32_ge(float a, float b)
{
    return rw_f32_le(b, a);
}

/* The same bit pattern (used for "is this cached constant still valid": stricter than ==). */
static inline bool rw_f32_same(float a, float b)
{
    return rw_f32_bits(a) == rw_f32_bits(b);
}

#endif /* RW_FLOAT_BITS_H */
