/*
 * rw_wire_units.c - SI floats to integer wire units by bit operations.
 */
#include "rw_wire_units.h"

#include <stdbool.h>

#include "rw_float_bits.h"

uint16_t rw_wire_u16_times(float x, uint32_t k_odd, int32_t k_shift)
{
    if (!rw_f32_positive(x)) {
        return 0u;
    }
    if (!rw_f32_finite(x)) {
        return 65535u;
    }
    int32_t exp2;
    const uint32_t p = rw_f32_mul_small(x, k_odd, k_shift, &exp2); /* x k = p 2^exp2, p <= 2^24 */
    if (exp2 >= 0) {
        return 65535u; /* >= 2^23 */
    }
    const uint32_t shift = (uint32_t)-exp2;
    if (shift >= 26u) {
        return 0u; /* < 0.5 */
    }
    const uint32_t rounded = (p + (1u << (shift - 1u))) >> shift;
    return rounded >= 65535u ? 65535u : (uint16_t)rounded;
}

int32_t rw_wire_i32_times(float x, uint32_t k_odd, int32_t k_shift)
{
    if (rw_f32_isnan(x)) {
        return 0;
    }
    const bool negative = (rw_f32_bits(x) & 0x80000000u) != 0u;
    uint32_t magnitude = 0x80000000u; /* saturated */
    if (rw_f32_finite(x)) {
        int32_t exp2;
        const uint32_t p = rw_f32_mul_small(x, k_odd, k_shift, &exp2);
        if (exp2 < 0) {
            magnitude = (uint32_t)-exp2 >= 32u ? 0u : p >> (uint32_t)-exp2;
        } else if (exp2 <= 7) {
            magnitude = p << (uint32_t)exp2; /* <= 2^31 */
        }
    }
    if (negative) {
        return magnitude >= 0x80000000u ? INT32_MIN : -(int32_t)magnitude;
    }
    return magnitude >= 0x80000000u ? INT32_MAX : (int32_t)magnitude;
}
