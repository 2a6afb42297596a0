/*
 * rw_pi_controller.h - PI controller with feed-forward input, output limits and anti-windup
 * (conditional integration plus an integrator clamp).
 *
 * In the rope speed loop: setpoint and measurement in m/s, output and feed-forward a throttle
 * fraction, kp in throttle per (m/s), ki_per_s in throttle per (m/s * s).
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
    rw_pi_controller_config cfg; /**< public, may be changed between steps */
    struct {
        float integral;    /**< integral term, output units (already multiplied by ki_per_s) */
        float output;      /**< last output, output units, always within [out_min, out_max] */
        int8_t saturation; /**< +1: last output at out_max, -1: at out_min, 0: inside */
        float ki_dt;       /**< ki_per_s * dt_s for ki_dt_ki_per_s and ki_dt_dt_s (computed once, not per step) */
        float ki_dt_ki_per_s; /**< the gain ki_dt belongs to */
        float ki_dt_dt_s;     /**< the dt_s ki_dt belongs to (0: none yet) */
    } state;               /**< private history */
} rw_pi_controller;

/** Copies cfg and resets. */
void rw_pi_controller_init(rw_pi_controller *c, const rw_pi_controller_config *cfg);
/** Fills cfg with the rope speed loop defaults of rw_defaults.h. */
void rw_pi_controller_config_defaults(rw_pi_controller_config *cfg);
/** Integral term and output back to 0, saturation cleared. */
void rw_pi_controller_reset(rw_pi_controller *c);
/**
 * One control step. setpoint and measurement in error units, feed_forward in output units,
 * dt_s the time since the previous step in seconds. Returns the output, within [out_min, out_max].
 */
float rw_pi_controller_step(rw_pi_controller *c, float setpoint, float measurement,
                            float feed_forward, float dt_s);
/** Last output without stepping. */
float rw_pi_controller_output(const rw_pi_controller *c);
/** true when the gains are finite and >= 0 and out_min <= out_max, both finite. */
bool rw_pi_controller_config_is_valid(const rw_pi_controller_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_PI_CONTROLLER_H */
