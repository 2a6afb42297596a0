#include "rw_params.h"

#include <math.h>

void rw_params_init_defaults(rw_params *p)
{
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        p->value[i] = rw_param_table[i].default_value;
    }
}

int rw_params_check(const rw_params *p, uint8_t param_id, float value, bool disarmed)
{
    (void)p;
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
