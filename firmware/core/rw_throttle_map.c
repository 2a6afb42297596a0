/*
 * rw_throttle_map.c - feed-forward throttle map and ESC pulse conversion.
 */
#include "rw_throttle_map.h"

#include "rw_defaults.h"

#include "rw_float_bits.h"

#include <stdint.h>
#include <string.h>

#define RW_TWO_PI_F 6.28318530718f
#define RW_S_PER_MIN_F 60.0f
/* The Q24 feed-forward factor saturates here (throttle per m/s; a sane drive needs 0.01-0.1). */
#define RW_THROTTLE_MAX_PER_MPS 127.0f

void rw_throttle_map_init(rw_throttle_map *m, const rw_throttle_map_config *cfg)
{
    m->cfg = *cfg;
    memset(&m->state, 0, sizeof m->state);
    rw_throttle_map_prepare(m);
}

void rw_throttle_map_config_defaults(rw_throttle_map_config *cfg)
{
    cfg->kv_rpm_per_v = RW_DEFAULT_MOTOR_KV_RPM_PER_V;
    cfg->wheel_radius_m = RW_DEFAULT_WHEEL_RADIUS_M;
    cfg->pulse_min_us = (uint16_t)RW_DEFAULT_ESC_PULSE_MIN_US;
    cfg->pulse_max_us = (uint16_t)RW_DEFAULT_ESC_PULSE_MAX_US;
}

bool rw_throttle_map_config_is_valid(const rw_throttle_map_config *cfg)
{
    return rw_f32_finite(cfg->kv_rpm_per_v) && cfg->kv_rpm_per_v > 0.0f && rw_f32_finite(cfg->wheel_radius_m) &&
           cfg->wheel_radius_m > 0.0f && cfg->pulse_min_us >= RW_ESC_PULSE_LIMIT_LOW_US &&
           cfg->pulse_min_us < cfg->pulse_max_us && cfg->pulse_max_us <= RW_ESC_PULSE_LIMIT_HIGH_US;
}

/* 2 pi r kv, or 0 when kv or r is not finite and positive (full speed = 2 pi r kv V, in m/min). */
static float two_pi_r_kv(float kv, float r_m)
{
    if (!rw_f32_positive_finite(kv) || !rw_f32_positive_finite(r_m)) {
        return 0.0f;
    }
    return RW_TWO_PI_F * r_m * kv;
}

/* 2 pi r kv V, i.e. 60 x the rope speed (m/s) at full throttle, or 0 when it cannot be computed. */
static float rope_m_per_min_at_full_throttle(float two_pi_r_kv_value, float battery_v)
{
    if (!rw_f32_positive_finite(battery_v) || !rw_f32_positive(two_pi_r_kv_value)) {
        return 0.0f;
    }
    const float full_m_per_min = two_pi_r_kv_value * battery_v; /* (2 pi r kv) V: the same product */
    return rw_f32_finite(full_m_per_min) ? full_m_per_min : 0.0f;
}

void rw_throttle_map_prepare_battery(rw_throttle_map *m, float battery_v)
{
    const float full_m_per_min = rope_m_per_min_at_full_throttle(m->state.two_pi_r_kv, battery_v);
    /* one soft-float division, once per battery voltage */
    m->state.throttle_per_mps = rw_f32_positive(full_m_per_min) ? RW_S_PER_MIN_F / full_m_per_min : 0.0f;
    const float per_mps = m->state.throttle_per_mps;
    m->state.throttle_per_mps_q24 = rw_f32_lt(per_mps, RW_THROTTLE_MAX_PER_MPS)
                                        ? (int32_t)(per_mps * 16777216.0f + 0.5f)
                                        : (int32_t)(RW_THROTTLE_MAX_PER_MPS * 16777216.0f);
    m->state.battery_v = battery_v;
}

static void effective_range_us(const rw_throttle_map *m, uint16_t *lo_us, uint16_t *hi_us);

void rw_throttle_map_prepare(rw_throttle_map *m)
{
    m->state.two_pi_r_kv = two_pi_r_kv(m->cfg.kv_rpm_per_v, m->cfg.wheel_radius_m);
    effective_range_us(m, &m->state.pulse_lo_us, &m->state.pulse_hi_us);
    rw_throttle_map_prepare_battery(m, m->state.battery_v);
}

int32_t rw_throttle_map_feed_forward(rw_throttle_map *m, int32_t rope_mps_q16, float battery_v)
{
    if (!rw_f32_same(battery_v, m->state.battery_v)) {
        rw_throttle_map_prepare_battery(m, battery_v);
    }
    const int32_t per_mps_q24 = m->state.throttle_per_mps_q24;
    if (rope_mps_q16 <= 0 || per_mps_q24 <= 0) {
        return 0;
    }
    const uint64_t throttle_q16 = (rw_mul_u32_u64((uint32_t)rope_mps_q16, (uint32_t)per_mps_q24) + (1u << 23)) >> 24;
    return throttle_q16 > RW_Q16_ONE ? RW_Q16_ONE : (int32_t)throttle_q16;
}

float rw_throttle_map_no_load_rope_mps(const rw_throttle_map *m, float throttle, float battery_v)
{
    if (!rw_f32_finite(throttle) || !(throttle > 0.0f)) {
        return 0.0f;
    }
    const float full_m_per_min = rope_m_per_min_at_full_throttle(m->state.two_pi_r_kv, battery_v);
    return (throttle > 1.0f ? 1.0f : throttle) * full_m_per_min / RW_S_PER_MIN_F;
}

/* The pulse range actually used: the configured one narrowed into the hard 1000..2000 us limits. */
static void effective_range_us(const rw_throttle_map *m, uint16_t *lo_us, uint16_t *hi_us)
{
    uint16_t lo = m->cfg.pulse_min_us;
    uint16_t hi = m->cfg.pulse_max_us;
    if (lo < RW_ESC_PULSE_LIMIT_LOW_US) {
        lo = (uint16_t)RW_ESC_PULSE_LIMIT_LOW_US;
    }
    if (lo > RW_ESC_PULSE_LIMIT_HIGH_US) {
        lo = (uint16_t)RW_ESC_PULSE_LIMIT_HIGH_US;
    }
    if (hi > RW_ESC_PULSE_LIMIT_HIGH_US) {
        hi = (uint16_t)RW_ESC_PULSE_LIMIT_HIGH_US;
    }
    if (hi < lo) {
        hi = lo;
    }
    *lo_us = lo;
    *hi_us = hi;
}

uint16_t rw_throttle_map_pulse_us(const rw_throttle_map *m, int32_t throttle_q16)
{
    const uint16_t lo_us = m->state.pulse_lo_us;
    const uint16_t hi_us = m->state.pulse_hi_us;
    if (throttle_q16 <= 0) {
        return lo_us;
    }
    if (throttle_q16 >= RW_Q16_ONE) {
        return hi_us;
    }
    /* round half up: throttle < 2^16 and span <= 1000, the product fits 32 bits */
    const uint32_t offset_us = ((uint32_t)throttle_q16 * (uint32_t)(hi_us - lo_us) + 32768u) >> 16;
    uint32_t pulse_us = (uint32_t)lo_us + offset_us;
    if (pulse_us > hi_us) {
        pulse_us = hi_us;
    }
    return (uint16_t)pulse_us;
}

uint16_t rw_throttle_map_pulse_third_us(const rw_throttle_map *m, int32_t throttle_q16)
{
    uint16_t lo_us;
    uint16_t hi_us;
    effective_range_us(m, &lo_us, &hi_us);
    const uint32_t lo = 3u * lo_us;
    const uint32_t hi = 3u * hi_us;
    if (throttle_q16 <= 0) {
        return (uint16_t)lo;
    }
    if (throttle_q16 >= RW_Q16_ONE) {
        return (uint16_t)hi;
    }
    /* round half up: throttle < 2^16 and span <= 3000 thirds, the product fits 32 bits */
    uint32_t pulse = lo + (((uint32_t)throttle_q16 * (hi - lo) + 32768u) >> 16);
    return (uint16_t)(pulse > hi ? hi : pulse);
}

float rw_throttle_map_throttle_from_pulse(const rw_throttle_map *m, uint16_t pulse_us)
{
    const uint16_t lo_us = m->state.pulse_lo_us;
    const uint16_t hi_us = m->state.pulse_hi_us;
    if (pulse_us <= lo_us || hi_us == lo_us) {
        return 0.0f;
    }
    if (pulse_us >= hi_us) {
        return 1.0f;
    }
    return (float)(pulse_us - lo_us) / (float)(hi_us - lo_us);
}
