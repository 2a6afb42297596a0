/*
 * rw_defaults.h - named default values of the small control blocks of the firmware core.
 *
 * One file for all defaults (SimpleFOC keeps its defaults.h the same way). Every value carries its
 * unit in the name. They are starting points for the real rig (15 mm wheels, one 64-edge encoder,
 * BLHeli_32 ESCs, 4S pack) and are overridden by the configuration stored in flash.
 * All values are single-precision float literals or integer literals: the board has no FPU.
 */
#ifndef RW_DEFAULTS_H
#define RW_DEFAULTS_H

/* ---- Rope drive geometry and sensing ---------------------------------------------------------- */

/** Radius of the rubber drive wheel that pushes the rope, metres. */
#define RW_DEFAULT_WHEEL_RADIUS_M 0.015f
/** Encoder edges counted per wheel revolution (all edges of the channel the capture unit sees). */
#define RW_DEFAULT_ENCODER_COUNTS_PER_REV 64u
/** The speed estimate is reported as 0 and flagged stale after this long without an encoder edge,
 *  microseconds (100 ms: one edge per 100 ms at 64 counts/rev is under 10 rpm). */
#define RW_DEFAULT_SPEED_TIMEOUT_US 100000u
/** Time constant of the low-pass on the M/T speed estimate, seconds (0 disables the filter). */
#define RW_DEFAULT_SPEED_FILTER_TAU_S 0.005f

/* ---- Motor, ESC and feed-forward --------------------------------------------------------------- */

/** Motor velocity constant, rpm per volt (no-load). */
#define RW_DEFAULT_MOTOR_KV_RPM_PER_V 1400.0f
/** Nominal battery voltage (4S LiPo), volts; only a documentation/default value, the map takes the
 *  measured voltage as an input. */
#define RW_DEFAULT_BATTERY_NOMINAL_V 14.8f
/** ESC pulse for zero throttle: the ESC's minimum, never output below it, microseconds. */
#define RW_DEFAULT_ESC_PULSE_MIN_US 1000u
/** ESC pulse for full throttle, microseconds. */
#define RW_DEFAULT_ESC_PULSE_MAX_US 2000u
/** Hard bounds every configured ESC pulse range must lie in, microseconds. */
#define RW_ESC_PULSE_LIMIT_LOW_US 1000u
#define RW_ESC_PULSE_LIMIT_HIGH_US 2000u

/* ---- Rope speed loop ---------------------------------------------------------------------------- */

/** Speed PI proportional gain, throttle fraction per (m/s) of rope speed error. */
#define RW_DEFAULT_SPEED_KP 0.02f
/** Speed PI integral gain, throttle fraction per (m/s * s) of rope speed error. */
#define RW_DEFAULT_SPEED_KI_PER_S 0.2f
/** Speed PI output limits, throttle fraction (feed-forward included). */
#define RW_DEFAULT_SPEED_OUT_MIN 0.0f
#define RW_DEFAULT_SPEED_OUT_MAX 1.0f

/** Rope speed setpoint ramp: rise and fall rates, (m/s) per second. */
#define RW_DEFAULT_SPEED_RAMP_UP_MPS_PER_S 10.0f
#define RW_DEFAULT_SPEED_RAMP_DOWN_MPS_PER_S 15.0f

/* ---- Takeoff velocity guard ---------------------------------------------------------------------- */

/** Takeoff velocity of the loop (0.221 g/m wool rope), m/s. */
#define RW_DEFAULT_TOV_MPS 2.6f
/** While airborne a speed setpoint must be at least tov_mps * margin (dimensionless, >= 1). */
#define RW_DEFAULT_TOV_MARGIN 1.2f
/** A measured speed under tov_mps for this long is a loop collapse, seconds. */
#define RW_DEFAULT_COLLAPSE_TIME_S 0.25f

#endif /* RW_DEFAULTS_H */
