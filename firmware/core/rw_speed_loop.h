/*
 * rw_speed_loop.h - the rope speed loop: M/T speed estimate, setpoint ramp (with the approach to the ToV
 * guard while airborne), PI with feed-forward and anti-windup, ESC pulse (never under the ESC minimum).
 *
 * One controller made of the small ones, public as SimpleFOC's FOCMotor holds its PID and filters:
 * estimator, ramp, pi and throttle are the parts, each with its public config; cfg holds what the loop
 * itself adds. After changing any config call rw_speed_loop_prepare (the core does, from
 * rw_core_apply_params): it converts every gain once for steps of dt_s, so the step itself runs in integers
 * (Q16.16 m/s) with no soft-float call and no check of the configuration.
 *
 * Per speed step (dt_s since the previous one), mode from the device state:
 *   OFF       the rope is not driven: ESC minimum, PI and ramp at rest (rw_speed_loop_reset)
 *   DRIVE     target -> ramp -> feed-forward + PI -> pulse
 *   AIRBORNE  the same, and the guard (cfg.guard_mps) bounds both ends: a setpoint above it comes down onto
 *             it exponentially (RW_SPEED_LOOP_GUARD_APPROACH_S, at least RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2),
 *             not at the full fall rate, and the throttle never goes under what holds the guard speed
 *             without load (the PI's lower limit, so its anti-windup knows the floor)
 *   LAND      target 0: ramp down; once the setpoint is 0 the ESC minimum and the PI at rest
 * Stale encoder: at a setpoint of at least RW_ENCODER_HOLD_MIN_MMPS, a silence longer than
 * RW_ENCODER_STALE_EDGE_PERIODS edge periods at the setpoint (and RW_ENCODER_STALE_MIN_US) means the reading
 * is stale, not that the rope stopped: pulse and PI are held until edges come back (the supervisor's
 * encoder_timeout_s decides when that is a fault). Those bounds are the protocol spec's constants.
 *
 * Portable core module: no Arduino header, no heap, reads no clock (times and dt_s come in).
 */
#ifndef RW_SPEED_LOOP_H
#define RW_SPEED_LOOP_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_mt_speed_estimator.h"
#include "rw_pi_controller.h"
#include "rw_ramp.h"
#include "rw_throttle_map.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Airborne, the setpoint approaches the guard speed exponentially with this time constant (s), at least
 * RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2: a step down to the guard then lands on it without undershooting. */
#define RW_SPEED_LOOP_GUARD_APPROACH_S 0.4f
#define RW_SPEED_LOOP_GUARD_APPROACH_MIN_MPS2 0.5f

typedef enum {
    RW_SPEED_LOOP_OFF = 0,      /**< the rope is not driven: ESC minimum */
    RW_SPEED_LOOP_DRIVE = 1,    /**< ramp to the target (spin-up) */
    RW_SPEED_LOOP_AIRBORNE = 2, /**< ramp to the target over the guard (the loop flies) */
    RW_SPEED_LOOP_LAND = 3,     /**< ramp to zero (spin-down, relax) */
} rw_speed_loop_mode;

/** Public configuration of the loop itself (the parts carry their own). */
typedef struct rw_speed_loop_config {
    float guard_mps; /**< airborne floor, m/s: ToV x margin (rw_tov_guard_min_airborne_mps) */
} rw_speed_loop_config;

typedef struct rw_speed_loop {
    rw_mt_speed_estimator estimator; /**< public part: encoder -> rope speed */
    rw_ramp ramp;                    /**< public part: setpoint rate limiter */
    rw_pi_controller pi;             /**< public part: PI, output = throttle fraction */
    rw_throttle_map throttle;        /**< public part: feed-forward and throttle -> ESC pulse */
    rw_speed_loop_config cfg;        /**< public; after a change call rw_speed_loop_prepare */
    struct {
        int32_t guard_q16;        /**< cfg.guard_mps, m/s Q16.16 (prepared) */
        uint64_t stale_bound_q16; /**< RW_ENCODER_STALE_EDGE_PERIODS edge periods x rope speed, us m/s Q16 (prepared) */
        float battery_v;          /**< the battery voltage the feed-forward uses (rw_speed_loop_set_battery) */
        int32_t setpoint_q16;     /**< ramped setpoint, m/s Q16.16 */
        uint16_t pulse_us;        /**< last ESC pulse */
        uint16_t pulse_third_us;  /**< the same in thirds of a microsecond (the PWM timer's resolution) */
    } state;                      /**< private: history and the prepared values */
} rw_speed_loop;

/** Every part with its defaults (rw_defaults.h), prepared for no step in particular, at rest. */
void rw_speed_loop_init(rw_speed_loop *loop);
/** Converts every config (the parts' and cfg) for speed steps of dt_s; the feed-forward's battery factor is
 *  kept for the battery voltage set last. Float arithmetic, once per change; a step of another dt_s still
 *  works (the parts convert for it, a few divisions). */
void rw_speed_loop_prepare(rw_speed_loop *loop, float dt_s);
/** The parts of rw_speed_loop_prepare, one each, for a change that touches one part (a PARAM_SET: the core
 *  prepares only the modules a parameter feeds, rw_params_modules): each converts its part's config in one
 *  piece, so a step sees a part's old or new values, never a mix.
 *    estimator: the M/T estimator (and its filter) for steps of dt_s, and the stale-reading bound (it
 *               depends on the wheel radius and the counts per turn): 1 float division (the filter's)
 *    ramp:      the ramp's steps for dt_s (multiplications)
 *    pi:        the PI's gains for dt_s (multiplications)
 *    throttle:  the throttle map's range and feed-forward factor at the battery voltage set last
 *               (1 float division)
 *    guard:     cfg.guard_mps in Q16.16 */
void rw_speed_loop_prepare_estimator(rw_speed_loop *loop, float dt_s);
void rw_speed_loop_prepare_ramp(rw_speed_loop *loop, float dt_s);
void rw_speed_loop_prepare_pi(rw_speed_loop *loop, float dt_s);
void rw_speed_loop_prepare_throttle(rw_speed_loop *loop);
void rw_speed_loop_prepare_guard(rw_speed_loop *loop);
/** The battery voltage the feed-forward uses from now on (one float division: call it off the speed step,
 *  when the reading has changed). */
void rw_speed_loop_set_battery(rw_speed_loop *loop, float battery_v);
/** One estimator step (rw_mt_speed_estimator_step): the encoder's cumulative count and last edge time, the
 *  step's time now_us and dt_s since the previous one. Returns the rope speed, m/s (>= 0). */
float rw_speed_loop_measure(rw_speed_loop *loop, uint32_t counts, uint32_t edge_us, uint32_t now_us, float dt_s);
/** At rest: PI reset, ramp and setpoint at 0, ESC minimum. */
void rw_speed_loop_reset(rw_speed_loop *loop);
/** Before a spin-up from rest: PI reset, the ramp starts from the measured speed (a wheel still turning). */
void rw_speed_loop_start(rw_speed_loop *loop);
/** One speed step (see above) towards target_mps, at now_us (the encoder's clock), dt_s since the previous
 *  step. Returns the ESC pulse, microseconds, never under throttle.cfg.pulse_min_us. */
uint16_t rw_speed_loop_step(rw_speed_loop *loop, rw_speed_loop_mode mode, float target_mps, uint32_t now_us,
                            float dt_s);
/** Last ESC pulse, microseconds. */
uint16_t rw_speed_loop_pulse_us(const rw_speed_loop *loop);
/** The same pulse in thirds of a microsecond (what a TCC1 output gives the ESCs); rounded half up to the
 *  microsecond it is rw_speed_loop_pulse_us. */
uint16_t rw_speed_loop_pulse_third_us(const rw_speed_loop *loop);
/** Ramped setpoint, m/s (exact: a Q16.16 value). */
float rw_speed_loop_setpoint_mps(const rw_speed_loop *loop);
/** Measured rope speed, m/s Q16.16 (the estimator's last step). */
int32_t rw_speed_loop_measured_q16(const rw_speed_loop *loop);
/** The battery voltage the feed-forward uses, V. */
float rw_speed_loop_battery_v(const rw_speed_loop *loop);

#ifdef __cplusplus
}
#endif

#endif /* RW_SPEED_LOOP_H */
