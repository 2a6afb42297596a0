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
    rw_ramp_config cfg; /**< public; after a change call rw_ramp_prepare */
    struct {
        int64_t y_q32;         /**< last output, units Q32 (the output: rounded to Q16.16) */
        int64_t step_up_q32;   /**< rate_up_per_s * prepared_dt_s, Q32 (INT64_MAX: no limit) */
        int64_t step_down_q32; /**< rate_down_per_s * prepared_dt_s, Q32 (INT64_MAX: no limit) */
        float prepared_dt_s;   /**< the step the two above are for (0: none; every step computes its own) */
    } state;                /**< private: history and the prepared steps */
} rw_ramp;

/** Copies cfg, prepares for no step in particular and resets the output to 0. */
void rw_ramp_init(rw_ramp *r, const rw_ramp_config *cfg);
/** Converts the rates for steps of dt_s (rate x dt_s in Q32, float arithmetic once): call it after changing
 *  cfg (the core does, from rw_core_apply_params). A step of that dt_s then costs integer arithmetic only; a
 *  step of another dt_s converts for itself (same result). dt_s <= 0 or not finite: for no step. */
void rw_ramp_prepare(rw_ramp *r, float dt_s);
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
