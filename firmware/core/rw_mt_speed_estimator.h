/*
 * rw_mt_speed_estimator.h - M/T (count plus period) wheel and rope speed estimator.
 *
 * Inputs per step, all from the encoder capture hardware and wrap-safe (uint32_t, modulo 2^32):
 *   count    cumulative number of encoder edges (one direction, wraps),
 *   edge_us  capture timestamp of the most recent of those edges, microseconds (wraps),
 *   now_us   time of this step on the same microsecond clock (wraps).
 * count and edge_us must be latched together (the same edge). Step at least every 2^31 us (about
 * 35 minutes; the firmware steps every tick); edge intervals (stops) of any length are handled.
 * Outputs: wheel rev/s, rpm and rope surface speed in m/s (2 pi r rev/s), optionally low-pass
 * filtered, and a "stale" flag. The step runs in integers (no soft-float on the Cortex-M0+): rev/s and
 * m/s in Q16.16 (1/65536: 15 um/s of rope), one 32-bit division chain per measured interval.
 * Portable core module: no Arduino header, no heap, reads no clock (times come in).
 */
#ifndef RW_MT_SPEED_ESTIMATOR_H
#define RW_MT_SPEED_ESTIMATOR_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_lowpass.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. */
typedef struct rw_mt_speed_estimator_config {
    uint32_t counts_per_rev; /**< encoder edges per wheel revolution (> 0) */
    uint32_t timeout_us;     /**< silent this long (no edge) -> speed 0 and stale, microseconds (> 0) */
    float wheel_radius_m;    /**< drive wheel radius, metres (> 0) */
    float filter_tau_s;      /**< low-pass time constant on rev/s, seconds; 0 = unfiltered */
} rw_mt_speed_estimator_config;

typedef struct rw_mt_speed_estimator {
    rw_mt_speed_estimator_config cfg; /**< public; after a change call rw_mt_speed_estimator_prepare */
    struct {
        uint32_t last_count;   /**< edge count at the last measured edge */
        uint32_t last_edge_us; /**< timestamp of that edge, microseconds */
        int32_t raw_rev_per_s_q16; /**< unfiltered estimate, rev/s Q16.16 (>= 0) */
        rw_lowpass filter;     /**< low-pass on raw_rev_per_s_q16, tau = filter_tau_s */
        bool primed;           /**< a reference edge has been latched since reset */
        bool stale;            /**< no measured edge interval since reset, or silent > timeout_us */
        bool valid;            /**< rw_mt_speed_estimator_config_is_valid(cfg) (prepared) */
        uint32_t two_pi_r_q32; /**< 2 pi wheel_radius_m, metres Q32; 0 for an invalid radius (prepared) */
        int32_t rope_mps_q16;  /**< filtered rope speed, m/s Q16.16 (2 pi r x the filtered rev/s) */
        uint32_t max_int_dt_us; /**< longest edge time the integer quotient takes: 2^24 / counts_per_rev (prepared) */
    } state;                   /**< private history */
} rw_mt_speed_estimator;

/** Copies cfg, prepares for no step in particular and resets. */
void rw_mt_speed_estimator_init(rw_mt_speed_estimator *e, const rw_mt_speed_estimator_config *cfg);
/** Converts cfg for steps of dt_s (the validity, 2 pi r in Q32, the filter's coefficient): call it after
 *  changing cfg (the core does, from rw_core_apply_params). A step of another dt_s filters with its own
 *  coefficient (rw_lowpass_prepare). */
void rw_mt_speed_estimator_prepare(rw_mt_speed_estimator *e, float dt_s);
/** Fills cfg with the defaults of rw_defaults.h (64 counts/rev, 15 mm wheel, ...). */
void rw_mt_speed_estimator_config_defaults(rw_mt_speed_estimator_config *cfg);
/** Speed 0, stale, no reference: the next step only latches count and edge time. */
void rw_mt_speed_estimator_reset(rw_mt_speed_estimator *e);
/**
 * One estimator step (see the law in the .c file). dt_s, the time since the previous step in
 * seconds, only drives the low-pass. Returns the (filtered) rope surface speed in m/s, >= 0.
 */
float rw_mt_speed_estimator_step(rw_mt_speed_estimator *e, uint32_t count, uint32_t edge_us,
                                 uint32_t now_us, float dt_s);
/** Filtered wheel speed, revolutions per second (>= 0). */
float rw_mt_speed_estimator_rev_per_s(const rw_mt_speed_estimator *e);
/** Filtered wheel speed, revolutions per minute (>= 0). */
float rw_mt_speed_estimator_rpm(const rw_mt_speed_estimator *e);
/** Filtered rope surface speed, m/s (>= 0): 2 pi wheel_radius_m rev/s. */
float rw_mt_speed_estimator_rope_mps(const rw_mt_speed_estimator *e);
/** The same, m/s Q16.16, as the last step (or reset) computed it: the speed loop's input. */
int32_t rw_mt_speed_estimator_rope_mps_q16(const rw_mt_speed_estimator *e);
/** Unfiltered wheel speed, rev/s (>= 0). */
float rw_mt_speed_estimator_raw_rev_per_s(const rw_mt_speed_estimator *e);
/** true while no edge interval has been measured since reset or the encoder was silent for
 *  longer than timeout_us (the speed then reads 0). */
bool rw_mt_speed_estimator_is_stale(const rw_mt_speed_estimator *e);
/** true when counts_per_rev > 0, timeout_us > 0, wheel_radius_m finite and > 0, filter_tau_s
 *  finite and >= 0. */
bool rw_mt_speed_estimator_config_is_valid(const rw_mt_speed_estimator_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_MT_SPEED_ESTIMATOR_H */
