/*
 * rw_ramp.h - setpoint rate limiter with separate rise and fall rates (units per second).
 *
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_RAMP_H
#define RW_RAMP_H

#include <stdbool.h>

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
        float y;            /**< last output, units */
        float step_up;      /**< rate_up_per_s * dt_s for the rate and dt_s below (computed once) */
        float step_up_rate_per_s; /**< the rate step_up belongs to */
        float step_up_dt_s;       /**< the dt_s step_up belongs to (0: none yet) */
        float step_down;    /**< rate_down_per_s * dt_s for the rate and dt_s below (computed once) */
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
/** Output set to y (start a ramp from the present measurement); a non-finite y resets to 0. */
void rw_ramp_reset_to(rw_ramp *r, float y);
/** Moves the output towards target by at most rate * dt_s; returns the new output. */
float rw_ramp_step(rw_ramp *r, float target, float dt_s);
/** Last output without stepping. */
float rw_ramp_output(const rw_ramp *r);
/** true when the last output equals target (the ramp has arrived). */
bool rw_ramp_at_target(const rw_ramp *r, float target);
/** true when both rates are finite; non-positive rates are valid and mean "unlimited". */
bool rw_ramp_config_is_valid(const rw_ramp_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_RAMP_H */
