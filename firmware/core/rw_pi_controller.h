/*
 * rw_pi_controller.h - PI controller with feed-forward input, output limits and anti-windup
 * (conditional integration plus an integrator clamp).
 *
 * In the rope speed loop: setpoint and measurement in m/s, output and feed-forward a throttle
 * fraction, kp in throttle per (m/s), ki_per_s in throttle per (m/s * s). The step runs in Q16.16 fixed
 * point (values x 65536 in an int32, range +-32768); the config stays float, converted by
 * rw_pi_controller_prepare when it changes (never in the step).
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_PI_CONTROLLER_H
#define RW_PI_CONTROLLER_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. */
typedef struct rw_pi_controller_config {
    float kp;       /**< proportional gain, output units per error unit */
    float ki_per_s; /**< integral gain, output units per (error unit * second) */
    float out_min;  /**< lower output limit, output units */
    float out_max;  /**< upper output limit, output units (>= out_min) */
} rw_pi_controller_config;

typedef struct rw_pi_controller {
    rw_pi_controller_config cfg; /**< public; after a change call rw_pi_controller_prepare */
    struct {
        int64_t integral_q32; /**< integral term, output units Q32 (already multiplied by ki_per_s) */
        int32_t output_q16;   /**< last output, output units Q16, always within the limits */
        int8_t saturation;    /**< +1: last output at out_max, -1: at out_min, 0: inside */
        bool valid;           /**< rw_pi_controller_config_is_valid(cfg), as prepared */
        int32_t kp_q24;       /**< kp, Q24 (prepared) */
        int64_t ki_dt_q32;    /**< ki_per_s * prepared_dt_s, Q32 (prepared) */
        float prepared_dt_s;  /**< the step ki_dt_q32 is for (0: none; every step converts its own) */
        int32_t out_min_q16;  /**< the lower limit in force, Q16: out_min prepared, or rw_pi_controller_set_out_min_q16 */
        int32_t out_max_q16;  /**< out_max, Q16 (prepared) */
    } state;                  /**< private: history and the prepared gains */
} rw_pi_controller;

/** Copies cfg, prepares for no step in particular and resets. */
void rw_pi_controller_init(rw_pi_controller *c, const rw_pi_controller_config *cfg);
/** Converts cfg for steps of dt_s: kp to Q24, ki_per_s dt_s to Q32, the limits to Q16, the validity (float
 *  arithmetic, once). Call it after changing cfg (the core does, from rw_core_apply_params). A step of that
 *  dt_s costs integer arithmetic only; a step of another dt_s converts its ki_per_s dt_s itself (same result).
 *  dt_s <= 0 or not finite: for no step in particular. */
void rw_pi_controller_prepare(rw_pi_controller *c, float dt_s);
/** A lower output limit that moves at run time (the speed loop's airborne floor), Q16, in force from the
 *  next step until the next prepare or call; kept at or under the upper limit. */
void rw_pi_controller_set_out_min_q16(rw_pi_controller *c, int32_t out_min_q16);
/** Fills cfg with the rope speed loop defaults of rw_defaults.h. */
void rw_pi_controller_config_defaults(rw_pi_controller_config *cfg);
/** Integral term and output back to 0 (0 brought into the limits), saturation cleared. */
void rw_pi_controller_reset(rw_pi_controller *c);
/**
 * One control step in Q16.16 fixed point (x 65536; no soft-float on the Cortex-M0+): setpoint and
 * measurement in error units, feed_forward in output units, dt_s the time since the previous step in
 * seconds. Returns the output, Q16, within [out_min, out_max] (the limits rounded to Q16).
 * Resolution: 1/65536 of an output unit for the output and the proportional term, 2^-32 for the
 * integral (so a small error still integrates), kp to 2^-24, ki_per_s dt_s to 2^-32.
 */
int32_t rw_pi_controller_step(rw_pi_controller *c, int32_t setpoint_q16, int32_t measurement_q16,
                              int32_t feed_forward_q16, float dt_s);
/** Last output without stepping, Q16. */
int32_t rw_pi_controller_output_q16(const rw_pi_controller *c);
/** The integral term in output units, to 2^-16 (for slow consumers such as the load-loss check). */
float rw_pi_controller_integral(const rw_pi_controller *c);
/** The same, Q16 (saturated to the int32 range). */
int32_t rw_pi_controller_integral_q16(const rw_pi_controller *c);
/** true when the gains are finite and >= 0 and out_min <= out_max, both finite. */
bool rw_pi_controller_config_is_valid(const rw_pi_controller_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_PI_CONTROLLER_H */
