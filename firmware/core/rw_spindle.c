#include "rw_spindle.h"

#include <math.h>
#include <string.h>

#include "rw_ax12.h"
#include "rw_float_bits.h"

/* Below this measured guide speed the guide counts as not moving (stall and homing checks), mm/s. */
#define RW_SPINDLE_STILL_MMPS 0.3f
/* Under this drive (a few tenths of a mm from the target) a stall is not judged: the guide barely moves.
 * 10 % of the moving speed register's 1023, rounded up: the register values whose drive is >= 10 %. */
#define RW_SPINDLE_MIN_STALL_DRIVE_RAW 103
/* Wheel-mode drive as a load threshold: 70 % of the drive, i.e. |load permille| 1023 >= 700 drive register. */
#define RW_SPINDLE_STALL_DRIVE_PERMILLE_PER_RAW 700
#define RW_SPINDLE_UM_PER_MM 1000.0f
/* Retracting, a load that holds within this distance of guide_max is the end of the stroke, not an object:
 * guide_max may sit on the hard stop (180 mm, the default), and the servo stalling on the stop reads as a
 * full load a little short of it (the position estimate is not exact). 2 mm of the 180 mm stroke. */
#define RW_SPINDLE_END_MARGIN_UM 2000
/* Saturation of the micrometre values derived from the config (+-2,000 m: far outside any stroke). */
#define RW_SPINDLE_MAX_UM 2000000000

/* mm (or mm/s) -> um (um/s), rounded half away from zero, saturated; NaN -> 0. Config and command time only. */
static int32_t to_um(float mm)
{
    if (rw_f32_isnan(mm)) {
        return 0;
    }
    const float um = mm * RW_SPINDLE_UM_PER_MM;
    if (rw_f32_ge(um, (float)RW_SPINDLE_MAX_UM)) {
        return RW_SPINDLE_MAX_UM;
    }
    if (rw_f32_le(um, -(float)RW_SPINDLE_MAX_UM)) {
        return -RW_SPINDLE_MAX_UM;
    }
    return rw_f32_lt(um, 0.0f) ? -(int32_t)(0.5f - um) : (int32_t)(um + 0.5f);
}

/* The smallest load (permille) whose load_pct = permille 0.1f is >= pct, as the float comparison decides
 * (NaN: never, 2000 is beyond the register). */
static int32_t load_threshold_permille(float pct)
{
    if (rw_f32_isnan(pct) || rw_f32_gt(pct, 200.0f)) {
        return 2000;
    }
    if (rw_f32_lt(pct, -200.0f)) {
        return -2000;
    }
    int32_t p = (int32_t)(pct * 10.0f);
    while ((float)(p - 1) * 0.1f >= pct) {
        --p;
    }
    while ((float)p * 0.1f < pct) {
        ++p;
    }
    return p;
}

/* The config in the step's integer units (see rw_spindle_derived); float arithmetic, once per change. */
static void derive(rw_spindle *s)
{
    const rw_spindle_config *c = &s->cfg;
    rw_spindle_derived *d = &s->state.derived;
    memset(d, 0, sizeof *d);
    const float lead = c->lead_mm_per_rev;
    if (rw_f32_positive_finite(lead) && rw_f32_le(lead, 1000.0f)) {
        const float mm_per_deg = lead / 360.0f;
        /* um per tick: lead 1000 / ticks per turn, Q32 (< 2^31 for leads up to 1000 mm) */
        d->um_per_tick_q32 = (uint32_t)(lead * (RW_SPINDLE_UM_PER_MM * 4294967296.0f / (float)RW_AX12_TICKS_PER_TURN));
        /* ticks/ms Q10 per um/s, Q8: ticks per um / 1000 x 1024 x 256 */
        d->ticks_per_ms_q10_per_umps_q8 =
            (int32_t)((float)RW_AX12_TICKS_PER_TURN * (1024.0f * 256.0f / 1.0e6f) / lead + 0.5f);
        /* moving speed register units per um/s, Q16: deg/s per um/s x register units per deg/s */
        const float raw_per_umps = RW_AX12_MOVING_UNITS_PER_DEG_S / (mm_per_deg * RW_SPINDLE_UM_PER_MM);
        d->moving_raw_per_umps_q16 = (uint32_t)(raw_per_umps * 65536.0f + 0.5f);
        d->full_scale_umps = d->moving_raw_per_umps_q16 == 0u
                                 ? INT32_MAX
                                 : (int32_t)(1023.5f * 65536.0f / (float)d->moving_raw_per_umps_q16) + 1;
        /* still: |speed| < 0.3 mm/s with speed = register 0.666 deg/s x mm_per_deg, as the float law said */
        int32_t still = 0;
        while (still <= 1023 && fabsf(rw_ax12_speed_deg_s((uint16_t)still) * mm_per_deg) < RW_SPINDLE_STILL_MMPS) {
            ++still;
        }
        d->still_speed_raw = still;
    } else {
        d->full_scale_umps = INT32_MAX; /* no valid lead: command register 0 */
        d->still_speed_raw = 1024;      /* and never moving */
    }
    const float kp_q16 = c->kp_per_s * 65536.0f;
    d->kp_per_s_q16 = rw_f32_isnan(kp_q16) ? 0
                                           : (rw_f32_ge(kp_q16, 2.0e9f) ? 2000000000
                                                                        : (rw_f32_le(kp_q16, -2.0e9f) ? -2000000000
                                                                                                      : (int32_t)kp_q16));
    d->guide_min_um = to_um(c->guide_min_mm);
    d->guide_max_um = to_um(c->guide_max_mm);
    d->tolerance_um = to_um(c->tolerance_mm);
    d->max_speed_umps = to_um(c->max_speed_mmps);
    d->homing_speed_umps = to_um(c->homing_speed_mmps);
    d->retract_speed_umps = to_um(c->retract_speed_mmps);
    d->homing_load_permille = load_threshold_permille(c->homing_load_pct);
    d->stall_load_permille = load_threshold_permille(c->stall_load_pct);
    d->secure_load_permille = load_threshold_permille(c->secure_load_pct);
    s->state.memo_cfg = *c;
}

/* The same config bit for bit (integer compares: no float compare, no call). */
static bool same_config(const rw_spindle_config *a, const rw_spindle_config *b)
{
    _Static_assert(sizeof(rw_spindle_config) == 13u * sizeof(float), "same_config compares every field");
    return rw_f32_same(a->lead_mm_per_rev, b->lead_mm_per_rev) &&
           rw_f32_same(a->guide_min_mm, b->guide_min_mm) &&
           rw_f32_same(a->guide_max_mm, b->guide_max_mm) &&
           rw_f32_same(a->kp_per_s, b->kp_per_s) &&
           rw_f32_same(a->max_speed_mmps, b->max_speed_mmps) &&
           rw_f32_same(a->tolerance_mm, b->tolerance_mm) &&
           rw_f32_same(a->homing_speed_mmps, b->homing_speed_mmps) &&
           rw_f32_same(a->homing_load_pct, b->homing_load_pct) &&
           rw_f32_same(a->stall_load_pct, b->stall_load_pct) &&
           rw_f32_same(a->stall_time_s, b->stall_time_s) &&
           rw_f32_same(a->secure_load_pct, b->secure_load_pct) &&
           rw_f32_same(a->retract_speed_mmps, b->retract_speed_mmps) &&
           rw_f32_same(a->timeout_s, b->timeout_s);
}

/* Derive again when the config changed. */
static void refresh_derived(rw_spindle *s)
{
    if (!same_config(&s->cfg, &s->state.memo_cfg)) {
        derive(s);
    }
}

void rw_spindle_init(rw_spindle *s, const rw_spindle_config *cfg)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    rw_multiturn_config turns;
    rw_multiturn_config_defaults(&turns);
    rw_multiturn_init(&s->state.turns, &turns);
    s->state.mode = RW_SPINDLE_IDLE;
    derive(s);
}

void rw_spindle_stop(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_IDLE;
    s->state.command_umps = 0;
    s->state.stall_ms = 0u;
}

void rw_spindle_home(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_HOMING;
    s->state.stall_ms = 0u;
}

void rw_spindle_move_to(rw_spindle *s, float target_mm)
{
    s->state.mode = RW_SPINDLE_POSITION;
    s->state.target_mm = target_mm;
    s->state.target_um = to_um(target_mm);
    s->state.target_reported = false;
    s->state.stall_ms = 0u;
}

void rw_spindle_retract(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_RETRACT;
    s->state.target_mm = s->cfg.guide_max_mm;
    s->state.target_um = to_um(s->cfg.guide_max_mm);
    s->state.stall_ms = 0u;
}

static int32_t abs_i32(int32_t x)
{
    return x < 0 ? -x : x;
}

static int32_t clamp_i32(int64_t x, int32_t lo, int32_t hi)
{
    return x < lo ? lo : (x > hi ? hi : (int32_t)x);
}

/* Guide speed (um/s, + = retract = counter-clockwise) -> wheel-mode moving speed register, rounded half up,
 * saturated at 1023 (rw_ax12_moving_speed_raw of the same speed in deg/s, to the rounding of the Q16 factor). */
static uint16_t moving_speed_raw(const rw_spindle_derived *d, int32_t command_umps)
{
    const int32_t magnitude_umps = abs_i32(command_umps);
    uint32_t raw = 1023u;
    if (magnitude_umps < d->full_scale_umps) {
        raw = ((uint32_t)magnitude_umps * d->moving_raw_per_umps_q16 + 32768u) >> 16;
        raw = raw > 1023u ? 1023u : raw;
    }
    return command_umps < 0 && raw != 0u ? (uint16_t)(raw | RW_AX12_DIRECTION_BIT) : (uint16_t)raw;
}

/* The guide position (um) of a multi-turn angle: (angle - home) x lead / turn, rounded. */
static int32_t position_um_of(const rw_spindle *s, int32_t angle_ticks)
{
    const int64_t delta_ticks = (int64_t)angle_ticks - (int64_t)s->state.home_ticks; /* |.| < 2^32 */
    const uint32_t magnitude = delta_ticks < 0 ? (uint32_t)(-delta_ticks) : (uint32_t)delta_ticks;
    const uint64_t product = rw_mul_u32_u64(magnitude, s->state.derived.um_per_tick_q32); /* < 2^63; inline */
    const int64_t um_q32 = (delta_ticks < 0 ? -(int64_t)product : (int64_t)product) + ((int64_t)1 << 31);
    return clamp_i32(um_q32 >> 32, -RW_SPINDLE_MAX_UM, RW_SPINDLE_MAX_UM);
}

/* A position in um as millimetres without a soft-float call (it runs every spindle step): round(um x 65.536), the
 * millimetres in Q16.16 (65.536 = 2199023256 / 2^25 to 2e-10), converted by bit operations (rw_f32_from_q16):
 * within 8e-6 mm of um / 1000, saturated at +-32767 mm (the guide's stroke is 180 mm). */
static float mm_of_um(int32_t um)
{
    const uint32_t magnitude = um < 0 ? 0u - (uint32_t)um : (uint32_t)um;
    const uint64_t q16 = (rw_mul_u32_u64(magnitude, 2199023256u) + ((uint64_t)1 << 24)) >> 25;
    const int32_t q = q16 > (uint64_t)INT32_MAX ? INT32_MAX : (int32_t)q16;
    return rw_f32_from_q16(um < 0 ? -q : q);
}

/* The stall/home condition: pushing against something (|load| over threshold) and not moving. A step without a
 * reading (a lost reply, the bus late) cannot see the load: the time held so far is kept, neither advanced nor
 * reset, so one lost reply neither restarts a homing stall nor lets a retract pull on past the secured load. */
static bool held_for(rw_spindle *s, bool measured, bool condition, uint32_t dt_ms)
{
    if (!measured) {
        return false;
    }
    const uint32_t held_ms = s->state.stall_ms + dt_ms;
    s->state.stall_ms = condition ? (held_ms < dt_ms ? UINT32_MAX : held_ms) : 0u;
    return rw_f32_ms_past(s->state.stall_ms, s->cfg.stall_time_s, true);
}

rw_spindle_outcome rw_spindle_step(rw_spindle *s, const rw_spindle_reading *reading, uint32_t dt_ms)
{
    refresh_derived(s);
    const rw_spindle_derived *d = &s->state.derived;
    rw_spindle_outcome outcome = RW_SPINDLE_NOTHING;
    int32_t load_permille = 0;
    bool switch_closed = false;
    const bool measured = reading != NULL;

    /* 1. measurement */
    if (reading != NULL) {
        s->state.answering = true;
        s->state.silent_ms = 0u;
        s->state.present_speed_raw = reading->speed_raw;
        const int32_t angle = rw_multiturn_step(&s->state.turns, true, rw_ax12_position_ticks(reading->position_raw),
                                                rw_ax12_speed_ticks_per_ms_q10(reading->speed_raw), dt_ms);
        s->state.position_um = position_um_of(s, angle);
        s->state.load_permille = rw_ax12_load_permille(reading->load_raw);
        load_permille = s->state.load_permille;
        switch_closed = reading->limit_switch;
    } else {
        const uint32_t silent_ms = s->state.silent_ms + dt_ms;
        s->state.silent_ms = silent_ms < dt_ms ? UINT32_MAX : silent_ms;
        /* dead reckoning from the commanded guide speed */
        const int64_t speed_q18 = (int64_t)s->state.command_umps * (int64_t)d->ticks_per_ms_q10_per_umps_q8;
        const int32_t speed_q10 = clamp_i32(speed_q18 >> 8, -RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10,
                                            RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10);
        const int32_t angle = rw_multiturn_step(&s->state.turns, false, 0, speed_q10, dt_ms);
        s->state.position_um = position_um_of(s, angle);
        if (rw_f32_ms_past(s->state.silent_ms, s->cfg.timeout_s, true)) {
            if (s->state.answering) {
                outcome = RW_SPINDLE_NO_ANSWER;
            }
            s->state.answering = false;
            rw_spindle_stop(s);
        }
    }
    const bool still = (int32_t)(s->state.present_speed_raw & RW_AX12_MAGNITUDE_MASK) < d->still_speed_raw;
    const int32_t pos_um = s->state.position_um;
    const int32_t abs_load = abs_i32(load_permille);

    /* 2. mode */
    int32_t cmd_umps = 0;
    switch ((rw_spindle_mode)s->state.mode) {
    case RW_SPINDLE_IDLE:
        break;
    case RW_SPINDLE_HOMING:
        cmd_umps = -d->homing_speed_umps;
        if (switch_closed || held_for(s, measured, abs_load >= d->homing_load_permille && still, dt_ms)) {
            s->state.home_ticks = s->state.turns.state.angle_ticks;
            s->state.position_um = 0;
            s->state.target_mm = 0.0f;
            s->state.target_um = 0;
            s->state.homed = true;
            outcome = switch_closed ? RW_SPINDLE_HOMED_BY_SWITCH : RW_SPINDLE_HOMED_BY_STALL;
            rw_spindle_stop(s);
            cmd_umps = 0;
        }
        break;
    case RW_SPINDLE_POSITION: {
        const int32_t error_um = clamp_i32((int64_t)s->state.target_um - pos_um, -RW_SPINDLE_MAX_UM, RW_SPINDLE_MAX_UM);
        if (abs_i32(error_um) <= d->tolerance_um) {
            cmd_umps = 0;
            s->state.stall_ms = 0u;
            if (!s->state.target_reported) {
                s->state.target_reported = true;
                outcome = RW_SPINDLE_TARGET_REACHED;
            }
        } else {
            s->state.target_reported = false;
            /* P law, rounded to the um/s: kp_per_s error */
            const int64_t cmd_q16 = rw_mul_s32_s64(d->kp_per_s_q16, error_um) + 32768;
            cmd_umps = clamp_i32(cmd_q16 >> 16, -d->max_speed_umps, d->max_speed_umps);
            /* wheel mode is open-loop drive: a blocked servo loads to about its drive level, which the P law
             * lowers near the target, so the stall threshold follows the drive (70 %; stall_load_pct caps it) */
            const int32_t drive_raw = (int32_t)(moving_speed_raw(d, cmd_umps) & RW_AX12_MAGNITUDE_MASK);
            const bool loaded = abs_load * 1023 >= RW_SPINDLE_STALL_DRIVE_PERMILLE_PER_RAW * drive_raw ||
                                abs_load >= d->stall_load_permille;
            if (held_for(s, measured, drive_raw >= RW_SPINDLE_MIN_STALL_DRIVE_RAW && loaded && still, dt_ms)) {
                outcome = RW_SPINDLE_STALLED;
                rw_spindle_stop(s);
                cmd_umps = 0;
            }
        }
        break;
    }
    case RW_SPINDLE_RETRACT:
        cmd_umps = d->retract_speed_umps;
        /* secured: the rope resists with at least secure_load_pct for stall_time_s (the load spike of
         * starting from rest is over within a few servo time constants, far less than that) */
        const bool at_end = pos_um >= d->guide_max_um - RW_SPINDLE_END_MARGIN_UM;
        if (held_for(s, measured, load_permille >= d->secure_load_permille, dt_ms)) {
            outcome = at_end ? RW_SPINDLE_STROKE_END : RW_SPINDLE_SECURED;
            rw_spindle_stop(s);
            cmd_umps = 0;
        } else if (pos_um >= d->guide_max_um) {
            outcome = RW_SPINDLE_STROKE_END;
            rw_spindle_stop(s);
            cmd_umps = 0;
        }
        break;
    }

    /* 3. soft limits (once homed, except while homing again): never drive further out of [min, max] */
    if (s->state.homed && s->state.mode != RW_SPINDLE_HOMING &&
        ((pos_um <= d->guide_min_um && cmd_umps < 0) || (pos_um >= d->guide_max_um && cmd_umps > 0))) {
        cmd_umps = 0;
    }
    s->state.command_umps = cmd_umps;
    s->state.moving_speed_raw = moving_speed_raw(d, cmd_umps);
    s->state.position_mm = mm_of_um(s->state.position_um); /* for the commands */
    return outcome;
}
