#include "rw_load_monitor.h"

#include <math.h>
#include <string.h>

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
    m->state.steady_s = 0.0f;
    m->state.drop_s = 0.0f;
}

void rw_load_monitor_prepare(rw_load_monitor *m, float dt_s)
{
    m->state.active = rw_f32_positive(m->cfg.drop_n) && rw_load_monitor_config_is_valid(&m->cfg);
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
 * resolution. */
static void lp_reset_to(rw_lowpass *f, float y)
{
    rw_lowpass_reset_to(f, rw_f32_to_q16(y));
}

static float lp_step(rw_lowpass *f, float x, float dt_s)
{
    return rw_f32_from_q16(rw_lowpass_step(f, rw_f32_to_q16(x), dt_s));
}

static float lp_output(const rw_lowpass *f)
{
    return rw_f32_from_q16(rw_lowpass_output_q16(f));
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

/* Comparisons and checks on bit patterns (rw_float_bits.h): on the M0+ every float compare is a libgcc call. */
bool rw_load_monitor_step(rw_load_monitor *m, bool steady, float integral, float battery_v, float dt_s)
{
    const rw_load_monitor_config *c = &m->cfg;
    if (!steady || !m->state.active || !rw_f32_finite(integral) || !rw_f32_finite(battery_v) ||
        !rw_f32_positive_finite(dt_s)) {
        if (m->state.steady || m->state.reported) {
            rw_load_monitor_reset(m);
        }
        return false;
    }
    if (!m->state.steady) { /* a new steady spell: start from here */
        m->state.steady = true;
        m->state.steady_s = 0.0f;
        m->state.drop_s = 0.0f;
        lp_reset_to(&m->state.battery, battery_v);
        float force0_n = c->n_per_v * integral * battery_v;
        lp_reset_to(&m->state.load, force0_n);
        lp_reset_to(&m->state.reference, force0_n);
    }
    float force_n = c->n_per_v * integral * lp_step(&m->state.battery, battery_v, dt_s);
    float load = lp_step(&m->state.load, force_n, dt_s);
    if (rw_f32_lt(m->state.steady_s, c->settle_s)) { /* learning: the PI is still settling */
        m->state.steady_s += dt_s;
        lp_reset_to(&m->state.reference, load);
        return false;
    }
    float reference = lp_output(&m->state.reference);
    if (rw_f32_ge(load, reference)) { /* rises: the reference climbs with rise_tau_s */
        lp_reset_to(&m->state.rise, reference);
        lp_reset_to(&m->state.reference, lp_step(&m->state.rise, load, dt_s));
        m->state.drop_s = 0.0f;
        return false;
    }
    if (rw_f32_gt(reference - load, c->drop_n)) {
        m->state.drop_s += dt_s; /* the reference holds while a drop is pending */
        if (rw_f32_ge(m->state.drop_s, c->time_s) && !m->state.reported) {
            m->state.reported = true;
            return true;
        }
        return false;
    }
    m->state.drop_s = 0.0f;
    (void)lp_step(&m->state.reference, load, dt_s);
    return false;
}

float rw_load_monitor_load_n(const rw_load_monitor *m)
{
    return lp_output(&m->state.load);
}

float rw_load_monitor_drop_n(const rw_load_monitor *m)
{
    return lp_output(&m->state.reference) - lp_output(&m->state.load);
}
