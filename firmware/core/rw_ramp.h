/*
 * rw_ramp.h - setpoint rate limiter with separate rise and fall rates (units per second).
 *
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_RAMP_H
#define RW_RAMP_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. A rate <= 0 or not finite means "no limit" in that direction. */
typedef struct rw_ramp_config {
    float rate_up_per_s;   /**< largest rise of the output, units per second */
    float rate_down_per_s; /**< largest fall of the output, units per second (a positive number) */
} rw_ramp_config;

typedef struct rw_ramp {
    rw_ramp_config cfg; /**< public, may be changed between steps */
    struct {
        int64_t y_q32;          /**< last output, units Q32 (the output: rounded to Q16.16) */
        int64_t step_up_q32;    /**< rate_up_per_s * dt_s, Q32, for the rate and dt_s below (computed once;
                                     INT64_MAX: no limit) */
        float step_up_rate_per_s; /**< the rate step_up_q16 belongs to */
        float step_up_dt_s;       /**< the dt_s step_up_q16 belongs to (0: none yet) */
        int64_t step_down_q32;  /**< rate_down_per_s * dt_s, Q32, for the rate and dt_s below */
        float step_down_rate_per_s;
        float step_down_dt_s;
    } state;                /**< private history */
} rw_ramp;

/** Copies cfg and resets the output to 0. */
void rw_ramp_init(rw_ramp *r, const rw_ramp_config *cfg);
/** Fills cfg with the rope speed setpoint ramp defaults of rw_defaults.h, (m/s) per second. */
void rw_ramp_config_defaults(rw_ramp_config *cfg);
/** Output back to 0. */
void rw_ramp_reset(rw_ramp *r);
/** Output set to y (start a ramp from the present measurement), rounded to Q16.16 (saturated at +-32768);
 *  a non-finite y resets to 0. */
void rw_ramp_reset_to(rw_ramp *r, float y);
/** Moves the output towards target_q16 (units, Q16.16) by at most rate * dt_s; returns the new output, Q16.16.
 *  Integer arithmetic (no soft-float on the Cortex-M0+): the output and rate * dt_s are kept to 2^-32 unit,
 *  so the ramp rate is exact to 1e-9 unit/step whatever the step; the output is that rounded to Q16.16. */
int32_t rw_ramp_step(rw_ramp *r, int32_t target_q16, float dt_s);
/** Last output without stepping, as a float (exact below 256 units). */
float rw_ramp_output(const rw_ramp *r);
/** Last output without stepping, Q16.16. */
int32_t rw_ramp_output_q16(const rw_ramp *r);
/** true when the last output equals target rounded to Q16.16 (the ramp has arrived). */
bool rw_ramp_at_target(const rw_ramp *r, float target);
/** true when both rates are finite; non-positive rates are valid and mean "unlimited". */
bool rw_ramp_config_is_valid(const rw_ramp_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_RAMP_H */
