/*
 * rw_defaults.h - named default values of the small control blocks of the firmware core.
 *
 * One file for all defaults (SimpleFOC keeps its defaults.h the same way). Every value carries its
 * unit in the name. They are starting points for the real rig (15 mm wheels, one 64-edge encoder,
 * BLHeli_32 ESCs, 3S pack) and are overridden by the configuration stored in flash.
 * All values are single-precision float literals or integer literals: the board has no FPU.
 */
#ifndef RW_DEFAULTS_H
#define RW_DEFAULTS_H

#include <stdint.h>

/* Values that are device parameters come from the protocol spec (one source): RW_PARAM_DEFAULT_* */
#include "rw_protocol.h"

/* ---- Rope drive geometry and sensing ---------------------------------------------------------- */

/** Radius of the rubber drive wheel that pushes the rope, metres. */
#define RW_DEFAULT_WHEEL_RADIUS_M RW_PARAM_DEFAULT_WHEEL_RADIUS_M
/** Encoder edges counted per wheel revolution (all edges of the channel the capture unit sees). */
#define RW_DEFAULT_ENCODER_COUNTS_PER_REV ((uint32_t)RW_PARAM_DEFAULT_ENCODER_COUNTS_PER_REV)
/** The speed estimate is reported as 0 and flagged stale after this long without an encoder edge,
 *  microseconds (100 ms: one edge per 100 ms at 64 counts/rev is under 10 rpm). */
#define RW_DEFAULT_SPEED_TIMEOUT_US 100000u
/** Time constant of the low-pass on the M/T speed estimate, seconds (0 disables the filter). */
#define RW_DEFAULT_SPEED_FILTER_TAU_S RW_PARAM_DEFAULT_SPEED_FILTER_TAU_S

/* ---- Motor, ESC and feed-forward --------------------------------------------------------------- */

/** Motor velocity constant, rpm per volt (no-load). */
#define RW_DEFAULT_MOTOR_KV_RPM_PER_V RW_PARAM_DEFAULT_MOTOR_KV_RPM_PER_V
/** Nominal battery voltage (3S LiPo), volts; only a documentation/default value, the map takes the
 *  measured voltage as an input. */
#define RW_DEFAULT_BATTERY_NOMINAL_V 11.1f
/** ESC pulse for zero throttle: the ESC's minimum, never output below it, microseconds. */
#define RW_DEFAULT_ESC_PULSE_MIN_US ((uint16_t)RW_PARAM_DEFAULT_ESC_MIN_US)
/** ESC pulse for full throttle, microseconds (the protocol's top, from the spec). */
#define RW_DEFAULT_ESC_PULSE_MAX_US RW_ESC_PULSE_MAX_US
/** Hard bounds every configured ESC pulse range must lie in, microseconds (the spec's ESC_PULSE_MIN/MAX_US). */
#define RW_ESC_PULSE_LIMIT_LOW_US RW_ESC_PULSE_MIN_US
#define RW_ESC_PULSE_LIMIT_HIGH_US RW_ESC_PULSE_MAX_US

/* ---- Rope speed loop ---------------------------------------------------------------------------- */

/** Speed PI proportional gain, throttle fraction per (m/s) of rope speed error. */
#define RW_DEFAULT_SPEED_KP RW_PARAM_DEFAULT_SPEED_KP
/** Speed PI integral gain, throttle fraction per (m/s * s) of rope speed error. */
#define RW_DEFAULT_SPEED_KI_PER_S RW_PARAM_DEFAULT_SPEED_KI
/** Speed PI output limits, throttle fraction (feed-forward included). */
#define RW_DEFAULT_SPEED_OUT_MIN 0.0f
#define RW_DEFAULT_SPEED_OUT_MAX 1.0f

/** Rope speed setpoint ramp: rise and fall rates, (m/s) per second. */
#define RW_DEFAULT_SPEED_RAMP_UP_MPS_PER_S RW_PARAM_DEFAULT_RAMP_UP_MPS2
#define RW_DEFAULT_SPEED_RAMP_DOWN_MPS_PER_S RW_PARAM_DEFAULT_RAMP_DOWN_MPS2

/* ---- Takeoff velocity guard ---------------------------------------------------------------------- */

/** Takeoff velocity of the loop (0.221 g/m wool rope), m/s. */
#define RW_DEFAULT_TOV_MPS RW_PARAM_DEFAULT_TOV_MPS
/** While airborne a speed setpoint must be at least tov_mps * margin (dimensionless, >= 1). */
#define RW_DEFAULT_TOV_MARGIN RW_PARAM_DEFAULT_TOV_MARGIN
/** A measured speed under tov_mps for this long is a loop collapse, seconds. */
#define RW_DEFAULT_COLLAPSE_TIME_S RW_PARAM_DEFAULT_COLLAPSE_TIME_S

#endif /* RW_DEFAULTS_H */
