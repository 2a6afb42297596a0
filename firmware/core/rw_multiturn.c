#include "rw_multiturn.h"

#include <math.h>

#include "rw_ax12.h"

void rw_multiturn_config_defaults(rw_multiturn_config *cfg)
{
    cfg->dead_zone_margin_deg = 10.0f; /* over the 60 degree zone a 10 % speed error drifts 6 degrees */
    cfg->max_jump_deg = 25.0f;
}

void rw_multiturn_init(rw_multiturn *m, const rw_multiturn_config *cfg)
{
    m->cfg = *cfg;
    rw_multiturn_reset(m);
}

void rw_multiturn_reset(rw_multiturn *m)
{
    m->state.angle_deg = 0.0f;
    m->state.initialized = false;
    m->state.dead_reckoning = false;
    m->state.rejected = 0u;
    m->state.agree = 0u;
    m->state.candidate_deg = 0.0f;
}

static float wrap360(float deg)
{
    float w = fmodf(deg, 360.0f);
    return w < 0.0f ? w + 360.0f : w;
}

static float wrap180(float deg)
{
    float w = wrap360(deg + 180.0f) - 180.0f;
    return w;
}

/* Count this reading into the run of readings that agree with each other (each within RW_MULTITURN_AGREE_DEG
 * of the previous one advanced by the measured speed); returns the run's length. */
static uint8_t agrees(rw_multiturn *m, float position_deg, float speed_deg_s, float dt_s)
{
    float expected = wrap360(m->state.candidate_deg + speed_deg_s * dt_s);
    bool same = m->state.agree > 0u && fabsf(wrap180(position_deg - expected)) <= RW_MULTITURN_AGREE_DEG;
    m->state.agree = same ? (uint8_t)(m->state.agree < 255u ? m->state.agree + 1u : 255u) : 1u;
    m->state.candidate_deg = position_deg;
    return m->state.agree;
}

float rw_multiturn_step(rw_multiturn *m, bool valid, float position_deg, float speed_deg_s, float dt_s)
{
    if (!isfinite(speed_deg_s) || !isfinite(dt_s) || dt_s < 0.0f) {
        speed_deg_s = 0.0f;
        dt_s = 0.0f;
    }
    float margin = m->cfg.dead_zone_margin_deg;
    bool reading_usable = valid && isfinite(position_deg) && position_deg >= margin &&
                          position_deg <= RW_AX12_VALID_RANGE_DEG - margin;
    if (!m->state.initialized) {
        /* no reference yet (e.g. powered up inside the dead zone): dead-reckon until enough usable readings
         * agree with each other to be the servo's, not dead-zone garbage */
        /* meanwhile the latest usable reading stands in (provisionally), else dead reckoning */
        m->state.angle_deg = reading_usable ? position_deg : m->state.angle_deg + speed_deg_s * dt_s;
        m->state.dead_reckoning = !reading_usable;
        if (reading_usable && agrees(m, position_deg, speed_deg_s, dt_s) >= RW_MULTITURN_AGREE) {
            m->state.angle_deg = position_deg;
            m->state.initialized = true;
            m->state.dead_reckoning = false;
            m->state.agree = 0u;
        }
        return m->state.angle_deg;
    }
    float predicted = m->state.angle_deg + speed_deg_s * dt_s;
    float w = wrap360(predicted);
    bool in_band = w >= RW_AX12_VALID_RANGE_DEG - margin || w < margin;
    m->state.dead_reckoning = in_band;
    if (in_band || !reading_usable) {
        m->state.angle_deg = predicted;
        return predicted;
    }
    float candidate = predicted + wrap180(position_deg - w);
    if (fabsf(candidate - predicted) > m->cfg.max_jump_deg) {
        ++m->state.rejected;
        /* rejected readings that keep agreeing with each other: the servo moved unobserved, believe them */
        m->state.angle_deg = agrees(m, position_deg, speed_deg_s, dt_s) >= RW_MULTITURN_AGREE ? candidate : predicted;
        if (m->state.angle_deg == candidate) {
            m->state.agree = 0u;
        }
        return m->state.angle_deg;
    }
    m->state.agree = 0u;
    m->state.angle_deg = candidate;
    return candidate;
}
