/*
 * rw_tov_guard.h - takeoff velocity (ToV) guard for the airborne loop.
 *
 * (a) Setpoint check: while airborne a rope speed setpoint is allowed only if it is at least
 *     tov_mps * margin. The guard never clamps: the caller answers a refused setpoint with a NACK
 *     (landing/relax are separate commands that do not go through this check).
 * (b) Collapse detector: a measured speed under tov_mps for longer than collapse_time_s reports a
 *     collapse once (an edge, for the LOOP_COLLAPSED event); it re-arms when the speed is back at or
 *     above tov_mps. Step it only while airborne; reset it when the loop becomes airborne.
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_TOV_GUARD_H
#define RW_TOV_GUARD_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. */
typedef struct rw_tov_guard_config {
    float tov_mps;         /**< takeoff velocity, m/s (> 0) */
    float margin;          /**< airborne setpoints must be >= tov_mps * margin (dimensionless, >= 1) */
    float collapse_time_s; /**< time under tov_mps that counts as a collapse, seconds (>= 0) */
} rw_tov_guard_config;

typedef struct rw_tov_guard {
    rw_tov_guard_config cfg; /**< public; after a change call rw_tov_guard_prepare */
    struct {
        float below_s;  /**< time the measured speed has been continuously under tov_mps, seconds */
        bool collapsed; /**< the collapse has been reported; cleared when the speed recovers */
        float min_airborne_mps;       /**< tov_mps * margin (prepared) */
        int32_t min_airborne_mps_q16; /**< the same, m/s Q16.16 (prepared) */
        bool config_valid;            /**< rw_tov_guard_config_is_valid(cfg) (prepared) */
    } state;            /**< private: history and the prepared values */
} rw_tov_guard;

/** Copies cfg, prepares and resets. */
void rw_tov_guard_init(rw_tov_guard *g, const rw_tov_guard_config *cfg);
/** tov_mps * margin (float and Q16.16) and the validity, computed from cfg: call it after changing cfg (the
 *  core does, from rw_core_apply_params); the step and the accessors use what it computed. */
void rw_tov_guard_prepare(rw_tov_guard *g);
/** Fills cfg with the defaults of rw_defaults.h. */
void rw_tov_guard_config_defaults(rw_tov_guard_config *cfg);
/** Timer cleared, detector re-armed. */
void rw_tov_guard_reset(rw_tov_guard *g);
/** Lowest setpoint allowed while airborne, m/s: tov_mps * margin. */
float rw_tov_guard_min_airborne_mps(const rw_tov_guard *g);
/** The same, m/s Q16.16 (rounded; kept with the product, so the fixed-point speed loop converts nothing). */
int32_t rw_tov_guard_min_airborne_mps_q16(const rw_tov_guard *g);
/** true when setpoint_mps is finite and >= tov_mps * margin; false otherwise (caller NACKs).
 *  Always false with an invalid config. */
bool rw_tov_guard_setpoint_allowed(const rw_tov_guard *g, float setpoint_mps);
/**
 * Collapse detector step with the measured rope speed (m/s) and dt_s since the previous step.
 * Returns true exactly once per collapse: on the step where the speed has been under tov_mps for
 * collapse_time_s; false otherwise.
 */
bool rw_tov_guard_step(rw_tov_guard *g, float measured_mps, float dt_s);
/** true from the reported collapse until the speed recovers (level, not edge). */
bool rw_tov_guard_is_collapsed(const rw_tov_guard *g);
/** true when tov_mps is finite and > 0, margin finite and >= 1, collapse_time_s finite and >= 0. */
bool rw_tov_guard_config_is_valid(const rw_tov_guard_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_TOV_GUARD_H */
