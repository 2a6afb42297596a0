#include "rw_ax12.h"

#include <math.h>

#define DEG_S_PER_RPM 6.0f

float rw_ax12_position_deg(uint16_t raw)
{
    uint16_t v = raw > 1023u ? 1023u : raw;
    return (float)v * RW_AX12_DEG_PER_POSITION_UNIT;
}

float rw_ax12_speed_deg_s(uint16_t raw)
{
    float magnitude = (float)(raw & RW_AX12_MAGNITUDE_MASK) * RW_AX12_RPM_PER_SPEED_UNIT * DEG_S_PER_RPM;
    return (raw & RW_AX12_DIRECTION_BIT) != 0u ? -magnitude : magnitude;
}

int16_t rw_ax12_load_permille(uint16_t raw)
{
    int16_t magnitude = (int16_t)(raw & RW_AX12_MAGNITUDE_MASK);
    return (raw & RW_AX12_DIRECTION_BIT) != 0u ? (int16_t)-magnitude : magnitude;
}

uint16_t rw_ax12_moving_speed_raw(float speed_deg_s)
{
    if (!isfinite(speed_deg_s)) {
        return 0u;
    }
    float units = fabsf(speed_deg_s) * RW_AX12_MOVING_UNITS_PER_DEG_S;
    uint16_t magnitude = units >= 1023.0f ? 1023u : (uint16_t)(units + 0.5f);
    return speed_deg_s < 0.0f && magnitude != 0u ? (uint16_t)(magnitude | RW_AX12_DIRECTION_BIT) : magnitude;
}

int32_t rw_ax12_position_ticks(uint16_t raw)
{
    const int32_t v = raw > 1023u ? 1023 : (int32_t)raw;
    return v * RW_AX12_TICKS_PER_POSITION_UNIT;
}

int32_t rw_ax12_speed_ticks_per_ms_q10(uint16_t raw)
{
    const int32_t magnitude = (int32_t)(raw & RW_AX12_MAGNITUDE_MASK) * RW_AX12_SPEED_UNIT_TICKS_PER_MS_Q10;
    return (raw & RW_AX12_DIRECTION_BIT) != 0u ? -magnitude : magnitude;
}
