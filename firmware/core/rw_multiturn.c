#include "rw_multiturn.h"

#include "rw_float_bits.h"

#define RW_MULTITURN_HALF_TURN_TICKS (RW_AX12_TICKS_PER_TURN / 2)
/* RW_MULTITURN_AGREE_DEG in ticks (3 x 8729.6, rounded) */
#define RW_MULTITURN_AGREE_TICKS 26189
/* dt_ms up to this keeps speed x dt within int32 (2^23 x 255 + 1023 < 2^31) */
#define RW_MULTITURN_INT32_DT_MS 255u

void rw_multiturn_config_defaults(rw_multiturn_config *cfg)
{
    cfg->dead_zone_margin_deg = 10.0f; /* over the 60 degree zone a 10 % speed error drifts 6 degrees */
    cfg->max_jump_deg = 25.0f;
}

void rw_multiturn_init(rw_multiturn *m, const rw_multiturn_config *cfg)
{
    m->cfg = *cfg;
    m->state.memo_margin_deg = 0.0f;
    m->state.memo_max_jump_deg = 0.0f;
    m->state.margin_ticks = 0;
    m->state.max_jump_ticks = 0;
    rw_multiturn_reset(m);
}

void rw_multiturn_reset(rw_multiturn *m)
{
    m->state.angle_ticks = 0;
    m->state.angle_rem_q10 = 0u;
    m->state.initialized = false;
    m->state.dead_reckoning = false;
    m->state.rejected = 0u;
    m->state.agree = 0u;
    m->state.candidate_ticks = 0;
    m->state.turn_base_ticks = 0;
}

float rw_multiturn_angle_deg(const rw_multiturn *m)
{
    return (float)m->state.angle_ticks * (1.0f / RW_AX12_TICKS_PER_DEG);
}

/* degrees -> ticks, rounded, for a config value (0 for NaN and negative values, saturated far above any
 * useful angle); run only when the config changes. */
static int32_t config_ticks(float deg)
{
    if (!rw_f32_positive(deg)) {
        return 0;
    }
    const float ticks = deg * RW_AX12_TICKS_PER_DEG + 0.5f;
    return rw_f32_lt(ticks, (float)RW_MULTITURN_MAX_TICKS) ? (int32_t)ticks : RW_MULTITURN_MAX_TICKS;
}

static void refresh_config(rw_multiturn *m)
{
    if (!rw_f32_same(m->cfg.dead_zone_margin_deg, m->state.memo_margin_deg) ||
        !rw_f32_same(m->cfg.max_jump_deg, m->state.memo_max_jump_deg)) {
        m->state.margin_ticks = config_ticks(m->cfg.dead_zone_margin_deg);
        m->state.max_jump_ticks = config_ticks(m->cfg.max_jump_deg);
        m->state.memo_margin_deg = m->cfg.dead_zone_margin_deg;
        m->state.memo_max_jump_deg = m->cfg.max_jump_deg;
    }
}

/* x wrapped into [-half turn, half turn) (x within a few turns: a few compares, no division). */
static int32_t wrap_half_turn(int32_t x)
{
    while (x >= RW_MULTITURN_HALF_TURN_TICKS) {
        x -= RW_AX12_TICKS_PER_TURN;
    }
    while (x < -RW_MULTITURN_HALF_TURN_TICKS) {
        x += RW_AX12_TICKS_PER_TURN;
    }
    return x;
}

static int32_t saturate_ticks(int64_t x)
{
    return x > RW_MULTITURN_MAX_TICKS ? RW_MULTITURN_MAX_TICKS
                                      : (x < -RW_MULTITURN_MAX_TICKS ? -RW_MULTITURN_MAX_TICKS : (int32_t)x);
}

/* speed x dt in whole ticks, the sub-tick remainder carried in *rem_q10 (floor division by 1024: the
 * remainder is always in [0, 1024), the sum over many steps exact). */
static int64_t advance_ticks(int32_t speed_q10, uint32_t dt_ms, uint16_t *rem_q10)
{
    if (speed_q10 > RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10) {
        speed_q10 = RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10;
    } else if (speed_q10 < -RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10) {
        speed_q10 = -RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10;
    }
    if (dt_ms <= RW_MULTITURN_INT32_DT_MS) {
        const int32_t total_q10 = speed_q10 * (int32_t)dt_ms + (int32_t)*rem_q10;
        *rem_q10 = (uint16_t)(total_q10 & 1023);
        return total_q10 >> 10; /* arithmetic shift: floor */
    }
    const int64_t total_q10 = (int64_t)speed_q10 * (int64_t)dt_ms + (int64_t)*rem_q10;
    *rem_q10 = (uint16_t)(total_q10 & 1023);
    return total_q10 >> 10;
}

/* Count this reading into the run of readings that agree with each other (each within RW_MULTITURN_AGREE_DEG
 * of the previous one advanced by the measured speed); returns the run's length. */
static uint8_t agrees(rw_multiturn *m, int32_t position_ticks, int64_t advance)
{
    const int64_t expected = (int64_t)m->state.candidate_ticks + advance;
    int32_t diff = 0;
    bool near = false;
    if (expected - position_ticks < 4 * RW_AX12_TICKS_PER_TURN && position_ticks - expected < 4 * RW_AX12_TICKS_PER_TURN) {
        diff = wrap_half_turn(position_ticks - (int32_t)expected);
        near = diff <= RW_MULTITURN_AGREE_TICKS && diff >= -RW_MULTITURN_AGREE_TICKS;
    } else { /* many turns in one step: wrap with a division (never on the tick path) */
        diff = (int32_t)(((int64_t)position_ticks - expected) % RW_AX12_TICKS_PER_TURN);
        diff = wrap_half_turn(diff);
        near = diff <= RW_MULTITURN_AGREE_TICKS && diff >= -RW_MULTITURN_AGREE_TICKS;
    }
    const bool same = m->state.agree > 0u && near;
    m->state.agree = same ? (uint8_t)(m->state.agree < 255u ? m->state.agree + 1u : 255u) : 1u;
    m->state.candidate_ticks = position_ticks;
    return m->state.agree;
}

/* angle_ticks := a, turn_base_ticks kept a whole number of turns with a - base in [0, one turn). */
static void set_angle(rw_multiturn *m, int32_t a)
{
    m->state.angle_ticks = a;
    int32_t w = a - m->state.turn_base_ticks;
    if (w < -4 * RW_AX12_TICKS_PER_TURN || w >= 5 * RW_AX12_TICKS_PER_TURN) { /* far: one division */
        int32_t turns = a / RW_AX12_TICKS_PER_TURN;
        if (a < 0 && turns * RW_AX12_TICKS_PER_TURN != a) {
            --turns;
        }
        m->state.turn_base_ticks = turns * RW_AX12_TICKS_PER_TURN;
        return;
    }
    while (w < 0) {
        w += RW_AX12_TICKS_PER_TURN;
        m->state.turn_base_ticks -= RW_AX12_TICKS_PER_TURN;
    }
    while (w >= RW_AX12_TICKS_PER_TURN) {
        w -= RW_AX12_TICKS_PER_TURN;
        m->state.turn_base_ticks += RW_AX12_TICKS_PER_TURN;
    }
}

int32_t rw_multiturn_step(rw_multiturn *m, bool valid, int32_t position_ticks, int32_t speed_ticks_per_ms_q10,
                          uint32_t dt_ms)
{
    refresh_config(m);
    const int32_t margin = m->state.margin_ticks;
    const bool reading_usable =
        valid && position_ticks >= margin && position_ticks <= RW_AX12_TICKS_VALID_RANGE - margin;
    const int64_t advance = advance_ticks(speed_ticks_per_ms_q10, dt_ms, &m->state.angle_rem_q10);
    const int32_t predicted = saturate_ticks((int64_t)m->state.angle_ticks + advance);
    if (!m->state.initialized) {
        /* no reference yet (e.g. powered up inside the dead zone): dead-reckon until enough usable readings
         * agree with each other to be the servo's, not dead-zone garbage */
        /* meanwhile the latest usable reading stands in (provisionally), else dead reckoning */
        set_angle(m, reading_usable ? position_ticks : predicted);
        m->state.dead_reckoning = !reading_usable;
        if (reading_usable && agrees(m, position_ticks, advance) >= RW_MULTITURN_AGREE) {
            m->state.initialized = true;
            m->state.dead_reckoning = false;
            m->state.agree = 0u;
        }
        return m->state.angle_ticks;
    }
    set_angle(m, predicted);
    const int32_t w = predicted - m->state.turn_base_ticks; /* predicted mod one turn */
    const bool in_band = w >= RW_AX12_TICKS_VALID_RANGE - margin || w < margin;
    m->state.dead_reckoning = in_band;
    if (in_band || !reading_usable) {
        return predicted;
    }
    const int32_t jump = wrap_half_turn(position_ticks - w);
    const int32_t candidate = saturate_ticks((int64_t)predicted + jump);
    if (jump > m->state.max_jump_ticks || jump < -m->state.max_jump_ticks) {
        ++m->state.rejected;
        /* rejected readings that keep agreeing with each other: the servo moved unobserved, believe them */
        if (agrees(m, position_ticks, advance) >= RW_MULTITURN_AGREE) {
            set_angle(m, candidate);
            m->state.agree = 0u;
        }
        return m->state.angle_ticks;
    }
    m->state.agree = 0u;
    set_angle(m, candidate);
    return candidate;
}
