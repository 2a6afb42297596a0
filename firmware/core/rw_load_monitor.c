#include "rw_load_monitor.h"

#include <math.h>

#include "rw_float_bits.h"

void rw_load_monitor_config_defaults(rw_load_monitor_config *cfg)
{
    cfg->n_per_v = rw_load_monitor_n_per_v(2.0f, 1250.0f, 0.085f, 0.015f);
    cfg->drop_n = 1.0f;
    cfg->time_s = 0.1f;
    cfg->filter_tau_s = RW_LOAD_MONITOR_FILTER_TAU_S;
    cfg->reference_tau_s = RW_LOAD_MONITOR_REFERENCE_TAU_S;
    cfg->rise_tau_s = RW_LOAD_MONITOR_RISE_TAU_S;
    cfg->battery_tau_s = RW_LOAD_MONITOR_BATTERY_TAU_S;
    cfg->settle_s = RW_LOAD_MONITOR_SETTLE_S;
}

void rw_load_monitor_init(rw_load_monitor *m, const rw_load_monitor_config *cfg)
{
    m->cfg = *cfg;
    rw_lowpass_config lp = { .tau_s = cfg->filter_tau_s };
    rw_lowpass_init(&m->state.load, &lp);
    lp.tau_s = cfg->reference_tau_s;
    rw_lowpass_init(&m->state.reference, &lp);
    lp.tau_s = cfg->rise_tau_s;
    rw_lowpass_init(&m->state.rise, &lp);
    lp.tau_s = cfg->battery_tau_s;
    rw_lowpass_init(&m->state.battery, &lp);
    rw_load_monitor_prepare(m, 0.0f);
    rw_load_monitor_reset(m);
}

void rw_load_monitor_reset(rw_load_monitor *m)
{
    rw_lowpass_reset(&m->state.load);
    rw_lowpass_reset(&m->state.reference);
    m->state.steady = false;
    m->state.reported = false;
    m->state.steady_q16 = 0;
    m->state.drop_q16 = 0;
}

void rw_load_monitor_prepare(rw_load_monitor *m, float dt_s)
{
    m->state.active = rw_f32_positive(m->cfg.drop_n) && rw_load_monitor_config_is_valid(&m->cfg);
    m->state.n_per_v_q16 = rw_f32_to_q16(m->cfg.n_per_v);
    m->state.drop_n_q16 = rw_f32_to_q16(m->cfg.drop_n);
    m->state.time_q16 = rw_f32_to_q16(m->cfg.time_s);
    m->state.settle_q16 = rw_f32_to_q16(m->cfg.settle_s);
    m->state.prepared_dt_s = rw_f32_positive_finite(dt_s) ? dt_s : 0.0f;
    m->state.dt_q16 = rw_f32_to_q16(m->state.prepared_dt_s);
    m->state.load.cfg.tau_s = m->cfg.filter_tau_s;
    m->state.reference.cfg.tau_s = m->cfg.reference_tau_s;
    m->state.rise.cfg.tau_s = m->cfg.rise_tau_s;
    m->state.battery.cfg.tau_s = m->cfg.battery_tau_s;
    rw_lowpass_prepare(&m->state.load, dt_s);
    rw_lowpass_prepare(&m->state.reference, dt_s);
    rw_lowpass_prepare(&m->state.rise, dt_s);
    rw_lowpass_prepare(&m->state.battery, dt_s);
}

float rw_load_monitor_n_per_v(float motor_count, float kv_rpm_per_v, float resistance_ohm, float wheel_radius_m)
{
    if (!(isfinite(motor_count) && isfinite(kv_rpm_per_v) && isfinite(resistance_ohm) && isfinite(wheel_radius_m)) ||
        motor_count <= 0.0f || kv_rpm_per_v <= 0.0f || resistance_ohm <= 0.0f || wheel_radius_m <= 0.0f) {
        return 0.0f;
    }
    /* Kt = 60 / (2 pi kv) N m/A; F = n Kt I / r with I = V / R */
    float kt_nm_per_a = 60.0f / (6.2831853f * kv_rpm_per_v);
    return motor_count * kt_nm_per_a / (resistance_ohm * wheel_radius_m);
}

/* The filters are the core's Q16.16 low-pass (rw_lowpass.h); forces in N and volts fit Q16.16 with 1.5e-5
 * resolution, and the whole step runs in those integers. */
static float lp_output(const rw_lowpass *f)
{
    return rw_f32_from_q16(rw_lowpass_output_q16(f));
}

static int32_t sat_i32(int64_t x)
{
    return x > INT32_MAX ? INT32_MAX : (x < INT32_MIN ? INT32_MIN : (int32_t)x);
}

/* F = n_per_v integral V, N Q16.16 (two 32 x 32 -> 64-bit products, saturated). */
static int32_t force_q16(int32_t n_per_v_q16, int32_t integral_q16, int32_t battery_q16)
{
    const int32_t volts_q16 = sat_i32(rw_mul_s32_s64(integral_q16, battery_q16) >> 16);
    return sat_i32(rw_mul_s32_s64(volts_q16, n_per_v_q16) >> 16);
}

/* t + dt, saturated just past limit (the timers only need to know they are past it). */
static int32_t timer_add(int32_t t_q16, int32_t dt_q16, int32_t limit_q16)
{
    return t_q16 >= limit_q16 ? t_q16 : t_q16 + dt_q16;
}

/* x finite and >= 0 (+0 included, -0 not), from the bit pattern: no soft-float call. */
static bool nonneg_finite(float x)
{
    return rw_f32_bits(x) < 0x7F800000u;
}

bool rw_load_monitor_config_is_valid(const rw_load_monitor_config *cfg)
{
    return rw_f32_positive_finite(cfg->n_per_v) && rw_f32_finite(cfg->drop_n) && nonneg_finite(cfg->time_s) &&
           nonneg_finite(cfg->filter_tau_s) && nonneg_finite(cfg->reference_tau_s) && nonneg_finite(cfg->rise_tau_s) &&
           nonneg_finite(cfg->battery_tau_s) && nonneg_finite(cfg->settle_s);
}

/* The law of rw_load_monitor.h in Q16.16: forces N, voltage V, times s. */
bool rw_load_monitor_step_q16(rw_load_monitor *m, bool steady, int32_t integral_q16, int32_t battery_q16, float dt_s)
{
    if (!steady || !m->state.active || !rw_f32_positive_finite(dt_s)) {
        if (m->state.steady || m->state.reported) {
            rw_load_monitor_reset(m);
        }
        return false;
    }
    const int32_t dt_q16 = rw_f32_same(dt_s, m->state.prepared_dt_s) ? m->state.dt_q16 : rw_f32_to_q16(dt_s);
    if (!m->state.steady) { /* a new steady spell: start from here */
        m->state.steady = true;
        m->state.steady_q16 = 0;
        m->state.drop_q16 = 0;
        rw_lowpass_reset_to(&m->state.battery, battery_q16);
        const int32_t force0 = force_q16(m->state.n_per_v_q16, integral_q16, battery_q16);
        rw_lowpass_reset_to(&m->state.load, force0);
        rw_lowpass_reset_to(&m->state.reference, force0);
    }
    const int32_t battery_f_q16 = rw_lowpass_step(&m->state.battery, battery_q16, dt_s);
    const int32_t load = rw_lowpass_step(&m->state.load, force_q16(m->state.n_per_v_q16, integral_q16, battery_f_q16), dt_s);
    if (m->state.steady_q16 < m->state.settle_q16) { /* learning: the PI is still settling */
        m->state.steady_q16 = timer_add(m->state.steady_q16, dt_q16, m->state.settle_q16);
        rw_lowpass_reset_to(&m->state.reference, load);
        return false;
    }
    const int32_t reference = rw_lowpass_output_q16(&m->state.reference);
    if (load >= reference) { /* rises: the reference climbs with rise_tau_s */
        rw_lowpass_reset_to(&m->state.rise, reference);
        rw_lowpass_reset_to(&m->state.reference, rw_lowpass_step(&m->state.rise, load, dt_s));
        m->state.drop_q16 = 0;
        return false;
    }
    if ((int64_t)reference - load > m->state.drop_n_q16) {
        m->state.drop_q16 = timer_add(m->state.drop_q16, dt_q16, m->state.time_q16); /* the reference holds */
        if (m->state.drop_q16 >= m->state.time_q16 && !m->state.reported) {
            m->state.reported = true;
            return true;
        }
        return false;
    }
    m->state.drop_q16 = 0;
    (void)rw_lowpass_step(&m->state.reference, load, dt_s);
    return false;
}

bool rw_load_monitor_step(rw_load_monitor *m, bool steady, float integral, float battery_v, float dt_s)
{
    const bool usable = rw_f32_finite(integral) && rw_f32_finite(battery_v);
    return rw_load_monitor_step_q16(m, steady && usable, usable ? rw_f32_to_q16(integral) : 0,
                                    usable ? rw_f32_to_q16(battery_v) : 0, dt_s);
}

float rw_load_monitor_load_n(const rw_load_monitor *m)
{
    return lp_output(&m->state.load);
}

float rw_load_monitor_drop_n(const rw_load_monitor *m)
{
    return lp_output(&m->state.reference) - lp_output(&m->state.load);
}
