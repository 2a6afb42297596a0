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

/* rw_params_check, then store on success. */
int rw_params_set(rw_params *p, uint8_t param_id, float value, bool disarmed);

static inline float rw_params_get(const rw_params *p, rw_param_id id)
{
    return p->value[id];
}

#endif /* RW_PARAMS_H */
