#include "rw_params.h"

#include <math.h>

/* Which prepare reads each parameter (rw_core_params.c): keep in step with it; tests/firmware_core/
 * test_core_param_apply.py compares every parameter's staged apply with a full one. */
static const uint16_t MODULES[RW_PARAM_COUNT] = {
    [RW_PARAM_TOV_MPS] = RW_PARAM_MODULE_TOV_GUARD,
    [RW_PARAM_TOV_MARGIN] = RW_PARAM_MODULE_TOV_GUARD,
    [RW_PARAM_COLLAPSE_TIME_S] = RW_PARAM_MODULE_TOV_GUARD,
    [RW_PARAM_SPEED_KP] = RW_PARAM_MODULE_SPEED_PI,
    [RW_PARAM_SPEED_KI] = RW_PARAM_MODULE_SPEED_PI,
    [RW_PARAM_RAMP_UP_MPS2] = RW_PARAM_MODULE_SPEED_RAMP,
    [RW_PARAM_RAMP_DOWN_MPS2] = RW_PARAM_MODULE_SPEED_RAMP,
    /* locked (DISARMED only): the speed loop is off while its three modules change */
    [RW_PARAM_WHEEL_RADIUS_M] = RW_PARAM_MODULE_SPEED_ESTIMATOR | RW_PARAM_MODULE_THROTTLE | RW_PARAM_MODULE_LOAD_MONITOR,
    [RW_PARAM_ENCODER_COUNTS_PER_REV] = RW_PARAM_MODULE_SPEED_ESTIMATOR,
    [RW_PARAM_HEARTBEAT_TIMEOUT_S] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_MAX_ROPE_SPEED_MPS] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_MOTOR_KV_RPM_PER_V] = RW_PARAM_MODULE_THROTTLE | RW_PARAM_MODULE_LOAD_MONITOR,
    [RW_PARAM_ESC_MIN_US] = RW_PARAM_MODULE_THROTTLE,
    [RW_PARAM_SPEED_FILTER_TAU_S] = RW_PARAM_MODULE_SPEED_ESTIMATOR,
    [RW_PARAM_TELEMETRY_RATE_HZ] = RW_PARAM_MODULE_TELEMETRY,
    [RW_PARAM_ARM_HOLD_S] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_ENCODER_TIMEOUT_S] = RW_PARAM_MODULE_SPEED_ESTIMATOR, /* and read by the supervisor */
    [RW_PARAM_LEAD_MM_PER_REV] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_GUIDE_MIN_MM] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_GUIDE_MAX_MM] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_SPINDLE_KP_PER_S] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_SPINDLE_MAX_SPEED_MMPS] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_SPINDLE_TOLERANCE_MM] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_HOMING_SPEED_MMPS] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_HOMING_LOAD_PCT] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_SPINDLE_STALL_LOAD_PCT] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_SPINDLE_STALL_TIME_S] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_GRASP_SECURE_LOAD_PCT] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_RELEASE_MM] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_RETRACT_SPEED_MMPS] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_BATTERY_CUTOFF_V] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_BATTERY_CUTOFF_TIME_S] = RW_PARAM_MODULE_NONE,
    [RW_PARAM_SPINDLE_TIMEOUT_S] = RW_PARAM_MODULE_SPINDLE,
    [RW_PARAM_LOAD_LOSS_DROP_N] = RW_PARAM_MODULE_LOAD_MONITOR,
    [RW_PARAM_LOAD_LOSS_TIME_S] = RW_PARAM_MODULE_LOAD_MONITOR,
    [RW_PARAM_DRIVE_RESISTANCE_OHM] = RW_PARAM_MODULE_LOAD_MONITOR,
};
_Static_assert(RW_PARAM_COUNT == 36u, "a new parameter needs its modules in MODULES (rw_params.c)");

uint16_t rw_params_modules(uint8_t param_id)
{
    return param_id < RW_PARAM_COUNT ? MODULES[param_id] : RW_PARAM_MODULE_NONE;
}

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
