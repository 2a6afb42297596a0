#include "rw_params.h"

#include <math.h>

void rw_params_init_defaults(rw_params *p)
{
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        p->value[i] = rw_param_table[i].default_value;
    }
}

/* The value of id with `value` standing in for parameter param_id. */
static float value_with(const rw_params *p, uint8_t param_id, float value, rw_param_id id)
{
    return param_id == (uint8_t)id ? value : p->value[id];
}

uint8_t rw_params_conflict(const rw_params *p, uint8_t param_id, float value)
{
    if (param_id == RW_PARAM_GUIDE_MIN_MM || param_id == RW_PARAM_GUIDE_MAX_MM) {
        if (!(value_with(p, param_id, value, RW_PARAM_GUIDE_MIN_MM) < value_with(p, param_id, value, RW_PARAM_GUIDE_MAX_MM))) {
            return param_id == RW_PARAM_GUIDE_MIN_MM ? (uint8_t)RW_PARAM_GUIDE_MAX_MM : (uint8_t)RW_PARAM_GUIDE_MIN_MM;
        }
    }
    if (param_id == RW_PARAM_TOV_MPS || param_id == RW_PARAM_TOV_MARGIN || param_id == RW_PARAM_MAX_ROPE_SPEED_MPS) {
        float guard_mps = value_with(p, param_id, value, RW_PARAM_TOV_MPS) * value_with(p, param_id, value, RW_PARAM_TOV_MARGIN);
        if (guard_mps > value_with(p, param_id, value, RW_PARAM_MAX_ROPE_SPEED_MPS)) {
            return param_id == RW_PARAM_MAX_ROPE_SPEED_MPS ? (uint8_t)RW_PARAM_TOV_MPS : (uint8_t)RW_PARAM_MAX_ROPE_SPEED_MPS;
        }
    }
    return (uint8_t)RW_PARAM_COUNT;
}

int rw_params_check(const rw_params *p, uint8_t param_id, float value, bool disarmed)
{
    if (param_id >= RW_PARAM_COUNT) {
        return RW_NACK_REASON_UNKNOWN_PARAM;
    }
    const rw_param_info *info = &rw_param_table[param_id];
    if (!isfinite(value) || value < info->min_value || value > info->max_value) {
        return RW_NACK_REASON_OUT_OF_RANGE;
    }
    if ((info->flags & RW_PARAM_FLAG_INTEGER) != 0u && floorf(value) != value) {
        return RW_NACK_REASON_OUT_OF_RANGE;
    }
    if ((info->flags & RW_PARAM_FLAG_LOCKED) != 0u && !disarmed) {
        return RW_NACK_REASON_PARAM_LOCKED;
    }
    if (rw_params_conflict(p, param_id, value) != (uint8_t)RW_PARAM_COUNT) {
        return RW_NACK_REASON_PARAM_CONFLICT;
    }
    return RW_DECODE_OK;
}

int rw_params_set(rw_params *p, uint8_t param_id, float value, bool disarmed)
{
    int result = rw_params_check(p, param_id, value, disarmed);
    if (result == RW_DECODE_OK) {
        p->value[param_id] = value;
    }
    return result;
}
