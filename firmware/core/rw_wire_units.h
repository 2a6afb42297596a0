/*
 * rw_wire_units.h - SI floats to the protocol's integer wire units (mm/s, rpm, um, ...), without soft-float
 * calls: x k for a constant k = k_odd 2^k_shift (1000 = 125 2^3, 60 = 15 2^2) from the float's bit pattern
 * (rw_f32_mul_small), rounded or truncated as the float product would be. On the M0+ a float multiply is a
 * libgcc call of ~120 instructions; telemetry converts eight values a frame.
 *
 * Portable core module: no Arduino header, no heap, stateless.
 */
#ifndef RW_WIRE_UNITS_H
#define RW_WIRE_UNITS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** x k rounded half up and saturated to 0..65535 (NaN and x <= 0 -> 0), k = k_odd 2^k_shift (k_odd odd, < 128). */
uint16_t rw_wire_u16_times(float x, uint32_t k_odd, int32_t k_shift);
/** (int32_t)(x k), truncated towards zero, k = k_odd 2^k_shift; NaN gives 0, beyond the int32 range saturates. */
int32_t rw_wire_i32_times(float x, uint32_t k_odd, int32_t k_shift);

#ifdef __cplusplus
}
#endif

#endif /* RW_WIRE_UNITS_H */
