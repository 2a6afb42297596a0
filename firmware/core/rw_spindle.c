#include "rw_spindle.h"

#include <math.h>
#include <string.h>

#include "rw_ax12.h"

/* Below this measured guide speed the guide counts as not moving (stall and homing checks), mm/s. */
#define RW_SPINDLE_STILL_MMPS 0.3f
/* Under this drive (a few tenths of a mm from the target) a stall is not judged: the guide barely moves. */
#define RW_SPINDLE_MIN_STALL_DRIVE_PCT 10.0f

void rw_spindle_init(rw_spindle *s, const rw_spindle_config *cfg)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    rw_multiturn_config turns;
    rw_multiturn_config_defaults(&turns);
    rw_multiturn_init(&s->state.turns, &turns);
    s->state.mode = RW_SPINDLE_IDLE;
}

void rw_spindle_stop(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_IDLE;
    s->state.command_mmps = 0.0f;
    s->state.stall_s = 0.0f;
}

void rw_spindle_home(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_HOMING;
    s->state.stall_s = 0.0f;
}

void rw_spindle_move_to(rw_spindle *s, float target_mm)
{
    s->state.mode = RW_SPINDLE_POSITION;
    s->state.target_mm = target_mm;
    s->state.target_reported = false;
    s->state.stall_s = 0.0f;
}

void rw_spindle_retract(rw_spindle *s)
{
    s->state.mode = RW_SPINDLE_RETRACT;
    s->state.target_mm = s->cfg.guide_max_mm;
    s->state.stall_s = 0.0f;
}

static float mm_per_deg(const rw_spindle *s)
{
    return s->cfg.lead_mm_per_rev / 360.0f;
}

static float clampf(float x, float lo, float hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* The stall/home condition: pushing against something (|load| over threshold) and not moving. */
static bool held_for(rw_spindle *s, bool condition, float dt_s)
{
    s->state.stall_s = condition ? s->state.stall_s + dt_s : 0.0f;
    return s->state.stall_s >= s->cfg.stall_time_s;
}

rw_spindle_outcome rw_spindle_step(rw_spindle *s, const rw_spindle_reading *reading, float dt_s)
{
    rw_spindle_outcome outcome = RW_SPINDLE_NOTHING;
    float load_pct = 0.0f;
    bool switch_closed = false;

    /* 1. measurement */
    if (reading != NULL) {
        s->state.answering = true;
        s->state.silent_s = 0.0f;
        float speed_deg_s = rw_ax12_speed_deg_s(reading->speed_raw);
        float angle = rw_multiturn_step(&s->state.turns, true, rw_ax12_position_deg(reading->position_raw),
                                        speed_deg_s, dt_s);
        s->state.position_mm = (angle - s->state.home_angle_deg) * mm_per_deg(s);
        s->state.speed_mmps = speed_deg_s * mm_per_deg(s);
        s->state.load_permille = rw_ax12_load_permille(reading->load_raw);
        load_pct = (float)s->state.load_permille * 0.1f;
        switch_closed = reading->limit_switch;
    } else {
        s->state.silent_s += dt_s;
        float angle = rw_multiturn_step(&s->state.turns, false, 0.0f, s->state.command_mmps / mm_per_deg(s), dt_s);
        s->state.position_mm = (angle - s->state.home_angle_deg) * mm_per_deg(s);
        if (s->state.silent_s >= s->cfg.timeout_s) {
            if (s->state.answering) {
                outcome = RW_SPINDLE_NO_ANSWER;
            }
            s->state.answering = false;
            rw_spindle_stop(s);
        }
    }
    bool still = fabsf(s->state.speed_mmps) < RW_SPINDLE_STILL_MMPS;
    float pos = s->state.position_mm;

    /* 2. mode */
    float cmd = 0.0f;
    switch ((rw_spindle_mode)s->state.mode) {
    case RW_SPINDLE_IDLE:
        break;
    case RW_SPINDLE_HOMING:
        cmd = -s->cfg.homing_speed_mmps;
        if (switch_closed || held_for(s, fabsf(load_pct) >= s->cfg.homing_load_pct && still, dt_s)) {
            s->state.home_angle_deg = s->state.turns.state.angle_deg;
            s->state.position_mm = 0.0f;
            s->state.target_mm = 0.0f;
            s->state.homed = true;
            outcome = switch_closed ? RW_SPINDLE_HOMED_BY_SWITCH : RW_SPINDLE_HOMED_BY_STALL;
            rw_spindle_stop(s);
            cmd = 0.0f;
        }
        break;
    case RW_SPINDLE_POSITION: {
        float error = s->state.target_mm - pos;
        if (fabsf(error) <= s->cfg.tolerance_mm) {
            cmd = 0.0f;
            s->state.stall_s = 0.0f;
            if (!s->state.target_reported) {
                s->state.target_reported = true;
                outcome = RW_SPINDLE_TARGET_REACHED;
            }
        } else {
            s->state.target_reported = false;
            cmd = clampf(s->cfg.kp_per_s * error, -s->cfg.max_speed_mmps, s->cfg.max_speed_mmps);
            /* wheel mode is open-loop drive: a blocked servo loads to about its drive level, which the P law
             * lowers near the target, so the stall threshold follows the drive (and stall_load_pct caps it) */
            float drive_pct = (float)(rw_ax12_moving_speed_raw(cmd / mm_per_deg(s)) & RW_AX12_MAGNITUDE_MASK) *
                              (100.0f / 1023.0f);
            float threshold_pct = 0.7f * drive_pct < s->cfg.stall_load_pct ? 0.7f * drive_pct : s->cfg.stall_load_pct;
            if (held_for(s, drive_pct >= RW_SPINDLE_MIN_STALL_DRIVE_PCT && fabsf(load_pct) >= threshold_pct && still,
                         dt_s)) {
                outcome = RW_SPINDLE_STALLED;
                rw_spindle_stop(s);
                cmd = 0.0f;
            }
        }
        break;
    }
    case RW_SPINDLE_RETRACT:
        cmd = s->cfg.retract_speed_mmps;
        /* secured: the rope resists with at least secure_load_pct for stall_time_s (the load spike of
         * starting from rest is over within a few servo time constants, far less than that) */
        if (held_for(s, load_pct >= s->cfg.secure_load_pct, dt_s)) {
            outcome = RW_SPINDLE_SECURED;
            rw_spindle_stop(s);
            cmd = 0.0f;
        } else if (pos >= s->cfg.guide_max_mm) {
            outcome = RW_SPINDLE_STROKE_END;
            rw_spindle_stop(s);
            cmd = 0.0f;
        }
        break;
    }

    /* 3. soft limits (once homed, except while homing again): never drive further out of [min, max] */
    if (s->state.homed && s->state.mode != RW_SPINDLE_HOMING &&
        ((pos <= s->cfg.guide_min_mm && cmd < 0.0f) || (pos >= s->cfg.guide_max_mm && cmd > 0.0f))) {
        cmd = 0.0f;
    }
    s->state.command_mmps = cmd;
    s->state.moving_speed_raw = rw_ax12_moving_speed_raw(cmd / mm_per_deg(s));
    return outcome;
}
