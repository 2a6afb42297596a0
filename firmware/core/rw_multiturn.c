#include "rw_multiturn.h"

#include <math.h>

#include "rw_ax12.h"

void rw_multiturn_config_defaults(rw_multiturn_config *cfg)
{
    cfg->dead_zone_margin_deg = 6.0f;
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
        /* no reference yet (e.g. powered up inside the dead zone): dead-reckon until a usable reading */
        m->state.angle_deg = reading_usable ? position_deg : m->state.angle_deg + speed_deg_s * dt_s;
        m->state.initialized = reading_usable;
        m->state.dead_reckoning = !reading_usable;
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
        m->state.angle_deg = predicted;
        return predicted;
    }
    m->state.angle_deg = candidate;
    return candidate;
}
