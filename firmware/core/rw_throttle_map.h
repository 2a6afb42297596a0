/*
 * rw_throttle_map.h - feed-forward throttle from rope speed (motor Kv, battery voltage, wheel
 * radius), and throttle fraction <-> ESC pulse width with the ESC minimum as a hard floor.
 *
 * Throttle fraction: 0 = ESC minimum pulse (motor stopped), 1 = full throttle (pulse_max_us); on the tick
 * path (feed-forward, pulse) in Q16.16 fixed point, the config float (converted by rw_throttle_map_prepare
 * when it changes, never on the tick path).
 * Portable core module: no Arduino header, no heap, reads no clock; stateless.
 */
#ifndef RW_THROTTLE_MAP_H
#define RW_THROTTLE_MAP_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. */
typedef struct rw_throttle_map_config {
    float kv_rpm_per_v;    /**< motor velocity constant, rpm per volt (> 0) */
    float wheel_radius_m;  /**< drive wheel radius, metres (> 0); the wheel sits on the motor shaft */
    uint16_t pulse_min_us; /**< ESC minimum = zero throttle, microseconds; never output below it */
    uint16_t pulse_max_us; /**< full throttle, microseconds (<= 2000) */
} rw_throttle_map_config;

typedef struct rw_throttle_map {
    rw_throttle_map_config cfg; /**< public; after a change call rw_throttle_map_prepare */
    struct {
        float two_pi_r_kv;      /**< 2 pi wheel_radius_m kv_rpm_per_v, 0 when not computable (prepared) */
        uint16_t pulse_lo_us;   /**< the pulse range in force: cfg's narrowed into 1000..2000 us (prepared) */
        uint16_t pulse_hi_us;
        float battery_v;        /**< the battery voltage throttle_per_mps is for (0: none yet) */
        float throttle_per_mps; /**< 60 / (2 pi r kv V): feed-forward throttle per m/s of rope (0: none) */
        int32_t throttle_per_mps_q24; /**< the same, Q24 (saturated at 127) */
    } state;                /**< private: prepared values only, the map has no history */
} rw_throttle_map;

/** Copies cfg and prepares. */
void rw_throttle_map_init(rw_throttle_map *m, const rw_throttle_map_config *cfg);
/** Converts cfg (2 pi r kv, the pulse range in force) and the factor for the battery voltage prepared last:
 *  call it after changing cfg (the core does, from rw_core_apply_params). */
void rw_throttle_map_prepare(rw_throttle_map *m);
/** Fills cfg with the defaults of rw_defaults.h. */
void rw_throttle_map_config_defaults(rw_throttle_map_config *cfg);
/**
 * Feed-forward throttle fraction in [0, 1] (Q16.16: 65536 = full throttle) that spins the unloaded motor so
 * the rope moves at rope_mps_q16 (m/s, Q16.16) on a battery of battery_v volts:
 *     throttle = 60 rope_mps / (2 pi wheel_radius_m kv_rpm_per_v battery_v), clamped to [0, 1],
 * evaluated as rope_mps * (60 / (2 pi r kv V)) in fixed point: the factor is kept in m->state for the last
 * battery voltage prepared (rw_throttle_map_prepare_battery), in Q24, so a call with that battery_v costs one
 * integer multiplication, no division and no soft-float call (resolution: 1/65536 of full throttle); another
 * battery_v prepares for itself first (one division).
 * Returns 0 for non-positive rope_mps_q16, non-finite or non-positive battery_v, or an invalid kv/radius.
 */
int32_t rw_throttle_map_feed_forward(rw_throttle_map *m, int32_t rope_mps_q16, float battery_v);
/** Computes the factor of rw_throttle_map_feed_forward for battery_v ahead of time (one division),
 *  so that the feed-forwards at this voltage need none. */
void rw_throttle_map_prepare_battery(rw_throttle_map *m, float battery_v);
/** Inverse of the feed-forward: unloaded rope speed (m/s, >= 0) at a throttle fraction (clamped
 *  to [0, 1]) and battery voltage; 0 for non-finite input or invalid config. */
float rw_throttle_map_no_load_rope_mps(const rw_throttle_map *m, float throttle, float battery_v);
/**
 * ESC pulse for a throttle fraction (Q16.16, 65536 = full): pulse_min_us + throttle (pulse_max_us -
 * pulse_min_us), rounded half up to the microsecond, in integers. Zero or negative throttle ->
 * pulse_min_us (bad input stops the motor), 1 and above -> pulse_max_us.
 * The result is never below pulse_min_us and never above 2000 us, whatever the input; with a
 * configured range outside 1000..2000 us the range is first narrowed into it.
 */
uint16_t rw_throttle_map_pulse_us(const rw_throttle_map *m, int32_t throttle_q16);
/**
 * The same pulse at the PWM timer's resolution, in thirds of a microsecond (TCC1 counts at 3 MHz): 3 pulse_min_us
 * + throttle 3 (pulse_max_us - pulse_min_us), rounded half up to the third. Same limits as rw_throttle_map_pulse_us;
 * rw_throttle_map_third_us_to_us of it is exactly what rw_throttle_map_pulse_us gives for the same throttle.
 */
uint16_t rw_throttle_map_pulse_third_us(const rw_throttle_map *m, int32_t throttle_q16);
/** A pulse in thirds of a microsecond rounded half up to the microsecond ((t + 1) / 3, without a division). */
static inline uint16_t rw_throttle_map_third_us_to_us(uint16_t pulse_third_us)
{
    /* (x 21846) >> 16 is x / 3 rounded down for x < 32768 (error under x / 98304 < 1/3) */
    return (uint16_t)((((uint32_t)pulse_third_us + 1u) * 21846u) >> 16);
}
/** Throttle fraction in [0, 1] of a pulse (inverse of rw_throttle_map_pulse_us). */
float rw_throttle_map_throttle_from_pulse(const rw_throttle_map *m, uint16_t pulse_us);
/** true when kv and radius are finite and > 0 and 1000 <= pulse_min_us < pulse_max_us <= 2000. */
bool rw_throttle_map_config_is_valid(const rw_throttle_map_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_THROTTLE_MAP_H */
