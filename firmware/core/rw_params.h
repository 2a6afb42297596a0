/* Device parameters: values in SI units, ranges and defaults from the generated table (protocol spec). */
#ifndef RW_PARAMS_H
#define RW_PARAMS_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_protocol.h"

typedef struct rw_params {
    float value[RW_PARAM_COUNT]; /* indexed by rw_param_id, SI units as in the spec */
} rw_params;

/* Every parameter to its spec default. */
void rw_params_init_defaults(rw_params *p);

/* Validate a new value: returns RW_DECODE_OK (0) or the NACK reason (UNKNOWN_PARAM, OUT_OF_RANGE,
 * PARAM_LOCKED, PARAM_CONFLICT). Never clamps: a value outside [min, max], NaN, infinity, or a fraction for
 * an integer parameter is refused; so is a value that breaks a rule with the other parameters as they are
 * (rw_params_conflict). */
int rw_params_check(const rw_params *p, uint8_t param_id, float value, bool disarmed);

/* The rules between parameters, checked with `value` in place of parameter param_id's current value:
 *   guide_min_mm < guide_max_mm                  (else no guide target is valid: every SET_LOOP is refused)
 *   tov_mps x tov_margin <= max_rope_speed_mps   (else no speed both flies and is accepted)
 * Returns the id of the other parameter of the first rule broken, or RW_PARAM_COUNT if none is. The
 * defaults sit at the far ends of the ranges, so a stored set that keeps the rules also loads in id order. */
uint8_t rw_params_conflict(const rw_params *p, uint8_t param_id, float value);

/* The modules a parameter feeds: what must be converted again (prepared) when it changes. Each bit is one
 * prepare the core runs in one piece (rw_core_params.c): a parameter's new value takes effect in its modules
 * at a tick boundary, never half-converted. A parameter read where it is used (heartbeat_timeout_s,
 * max_rope_speed_mps, arm_hold_s, release_mm, battery_cutoff_v, battery_cutoff_time_s) feeds none. */
#define RW_PARAM_MODULE_NONE 0x0000u
#define RW_PARAM_MODULE_SPEED_ESTIMATOR 0x0001u /* M/T estimator, its filter and the stale-reading bound */
#define RW_PARAM_MODULE_SPEED_RAMP 0x0002u      /* setpoint ramp steps */
#define RW_PARAM_MODULE_SPEED_PI 0x0004u        /* speed PI gains */
#define RW_PARAM_MODULE_THROTTLE 0x0008u        /* feed-forward throttle map (battery factor) and ESC range */
#define RW_PARAM_MODULE_TOV_GUARD 0x0010u       /* ToV guard and the speed loop's airborne floor, together */
#define RW_PARAM_MODULE_SPINDLE 0x0020u         /* spindle position loop config */
#define RW_PARAM_MODULE_LOAD_MONITOR 0x0040u    /* load-loss monitor */
#define RW_PARAM_MODULE_TELEMETRY 0x0080u       /* telemetry period */
#define RW_PARAM_MODULE_ALL 0x00FFu
/* The speed loop's own modules: a parameter settable in flight feeds at most one of them. */
#define RW_PARAM_MODULES_SPEED_LOOP                                                                              \
    (RW_PARAM_MODULE_SPEED_ESTIMATOR | RW_PARAM_MODULE_SPEED_RAMP | RW_PARAM_MODULE_SPEED_PI |                 \
     RW_PARAM_MODULE_THROTTLE | RW_PARAM_MODULE_TOV_GUARD)

/* The RW_PARAM_MODULE_* bits of param_id (RW_PARAM_MODULE_NONE for an unknown id). */
uint16_t rw_params_modules(uint8_t param_id);

/* rw_params_check, then store on success. */
int rw_params_set(rw_params *p, uint8_t param_id, float value, bool disarmed);

static inline float rw_params_get(const rw_params *p, rw_param_id id)
{
    return p->value[id];
}

#endif /* RW_PARAMS_H */
