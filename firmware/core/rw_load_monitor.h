/*
 * rw_load_monitor.h - load-loss detector of the rope drive: a rope that breaks (or an object that slips off
 * the loop) while the loop is flying takes its load off the wheels; the speed loop holds the speed and its
 * integrator lets go of the load's throttle. This watches that integrator.
 *
 * Load estimate (rope force at the wheels, N), from what the speed loop already has:
 *   F = n_per_v * integral * low-pass(battery_v, battery_tau_s)
 * integral: the speed PI's integral term (throttle fraction), which at a steady speed holds the throttle
 * the feed-forward (the no-load kv map) does not give: motor friction, the ESC's dead band and the rope's
 * load. integral * battery_v is the extra drive voltage, I R; n_per_v = motor_count Kt / (R r) turns it
 * into rope force (2 motors, Kt = 60 / (2 pi kv), R winding + ESC per motor, r wheel radius: 12 N/V for
 * 1250 rpm/V, 0.085 ohm, 15 mm). The estimate carries a constant offset (friction, dead band: about
 * 1.6 N on the reference rig): only its changes are judged, never its level. The battery voltage is
 * filtered as the integral follows it: after a sag the same I R is a larger throttle fraction, which the
 * integrator reaches in about 0.3 s; with the instantaneous voltage a fast sag (12 V to 9.4 V in 50 ms)
 * would read as a 1 N load drop.
 *
 * Discrete law, per speed-loop step of dt_s, while steady (airborne, setpoint not moving, PI not saturated):
 *   load      <- low-pass(F, filter_tau_s)
 *   reference <- low-pass(load, rise_tau_s)           if load >= reference (an object caught)
 *                low-pass(load, reference_tau_s)      otherwise, unless a drop is pending (then held)
 *   drop = reference - load;  drop > drop_n for time_s -> load lost (reported once)
 * For settle_s after the monitor becomes steady (spin-up done, a speed step ended) the reference is the
 * load (learnt, nothing judged): the PI settles after a setpoint change. A load that fades slower than
 * reference_tau_s is not a loss; a rise shorter than rise_tau_s (the PI catching a battery sag or a speed
 * dip and letting go again) hardly lifts the reference, so its return is not a loss either. Not steady: the
 * monitor restarts (the next steady spell learns anew).
 * drop_n <= 0 disables it.
 *
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_LOAD_MONITOR_H
#define RW_LOAD_MONITOR_H

#include <stdbool.h>

#include "rw_lowpass.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Fixed time constants of the detector (seconds); the thresholds are device parameters. */
#define RW_LOAD_MONITOR_FILTER_TAU_S 0.05f    /* load estimate low-pass: PWM and speed noise */
#define RW_LOAD_MONITOR_REFERENCE_TAU_S 2.0f  /* slower fades are load changes, not losses */
#define RW_LOAD_MONITOR_RISE_TAU_S 0.3f       /* the reference climbs to a new load this fast */
#define RW_LOAD_MONITOR_BATTERY_TAU_S 0.3f    /* the speed PI's integral follows a battery step about this fast */
#define RW_LOAD_MONITOR_SETTLE_S 0.5f         /* the speed PI settles within this after a setpoint step */

/** Public configuration. */
typedef struct rw_load_monitor_config {
    float n_per_v;          /**< rope force per volt of drive residual, N/V (> 0) */
    float drop_n;           /**< a load drop over this is a loss, N (<= 0: monitor off) */
    float time_s;           /**< the drop must last this long, s (>= 0) */
    float filter_tau_s;     /**< load estimate low-pass, s */
    float reference_tau_s;  /**< reference decay, s */
    float rise_tau_s;       /**< reference rise, s */
    float battery_tau_s;    /**< battery voltage low-pass, s */
    float settle_s;         /**< learning time after becoming steady, s */
} rw_load_monitor_config;

typedef struct rw_load_monitor {
    rw_load_monitor_config cfg; /**< public; after a change call rw_load_monitor_prepare */
    struct {
        rw_lowpass load;      /**< filtered load estimate, N */
        rw_lowpass reference; /**< reference level, N (its filter: falls, reference_tau_s) */
        rw_lowpass rise;      /**< the reference's filter for rises (rise_tau_s): holds the memoised alpha */
        rw_lowpass battery;   /**< battery voltage as the integral follows it, V */
        bool steady;          /**< the previous step was steady */
        bool reported;        /**< the loss was reported (once per steady spell) */
        bool active;          /**< the configuration is valid and drop_n > 0 (prepared) */
        int32_t steady_q16;   /**< time steady, s Q16.16 (saturates past settle_s) */
        int32_t drop_q16;     /**< time the drop has exceeded drop_n, s Q16.16 (saturates past time_s) */
        int32_t n_per_v_q16;  /**< n_per_v, N/V Q16.16 (prepared) */
        int32_t drop_n_q16;   /**< drop_n, N Q16.16 (prepared) */
        int32_t time_q16;     /**< time_s, s Q16.16 (prepared) */
        int32_t settle_q16;   /**< settle_s, s Q16.16 (prepared) */
        float prepared_dt_s;  /**< the step dt_q16 is for (0: none) */
        int32_t dt_q16;       /**< prepared_dt_s, s Q16.16 */
    } state;                  /**< private history */
} rw_load_monitor;

/** Copies cfg, prepares for no step in particular and resets. */
void rw_load_monitor_init(rw_load_monitor *m, const rw_load_monitor_config *cfg);
/** Fills cfg with the reference rig's values (n_per_v for 1250 rpm/V, 0.085 ohm, 15 mm; drop 1.0 N, 0.1 s). */
void rw_load_monitor_config_defaults(rw_load_monitor_config *cfg);
/** Forget the learnt levels: the next steady step starts learning. */
void rw_load_monitor_reset(rw_load_monitor *m);
/** Converts cfg for steps of dt_s: the filters' time constants and coefficients (four float divisions, so that
 *  steps of this dt_s do none) and whether the monitor is on; call it after changing cfg (the core does, from
 *  rw_core_apply_params). */
void rw_load_monitor_prepare(rw_load_monitor *m, float dt_s);
/** n_per_v for motor_count motors of kv_rpm_per_v behind resistance_ohm each, on wheels of wheel_radius_m;
 *  0 when an argument is not finite and > 0. */
float rw_load_monitor_n_per_v(float motor_count, float kv_rpm_per_v, float resistance_ohm, float wheel_radius_m);
/**
 * One step in fixed point (the core's: no soft-float call): integral_q16 the speed PI's integral term
 * (throttle fraction, Q16.16), battery_q16 the feed-forward's battery voltage (V, Q16.16); otherwise as
 * rw_load_monitor_step.
 */
bool rw_load_monitor_step_q16(rw_load_monitor *m, bool steady, int32_t integral_q16, int32_t battery_q16, float dt_s);
/**
 * One speed-loop step. steady: airborne at a setpoint that is not moving, PI not saturated (else the monitor
 * restarts and returns false). integral: the speed PI's integral term (throttle fraction); battery_v: the
 * battery voltage the feed-forward uses (V); dt_s since the previous step. Returns true once, on the step
 * where the load has been more than drop_n under its reference for time_s.
 */
bool rw_load_monitor_step(rw_load_monitor *m, bool steady, float integral, float battery_v, float dt_s);
/** Filtered load estimate, N (offset included). */
float rw_load_monitor_load_n(const rw_load_monitor *m);
/** reference - load, N (how far the load has fallen). */
float rw_load_monitor_drop_n(const rw_load_monitor *m);
/** true when every field is finite, n_per_v > 0 and the times >= 0. */
bool rw_load_monitor_config_is_valid(const rw_load_monitor_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_LOAD_MONITOR_H */
