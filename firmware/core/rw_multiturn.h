/* Multi-turn angle of the AX-12A output from its single-turn position register.
 *
 * The register covers 0-300 degrees; over the remaining 60 degrees (the dead zone) it reads garbage, so
 * it cannot count turns on its own. Each step predicts the angle from the measured speed; inside the dead
 * zone (plus a margin) the prediction is the estimate (dead reckoning); outside it the reading is unwrapped
 * to the turn nearest the prediction, which re-synchronises after the dead zone; a reading farther than
 * max_jump_deg from the prediction is rejected as impossible and counted.
 *
 * A single reading is never trusted on its own where it could be garbage: the first reference is taken only
 * once RW_MULTITURN_AGREE consecutive readings agree with each other (advanced by the measured speed), and
 * so is a re-synchronisation after the servo moved unobserved (readings that keep being rejected but agree
 * with each other: the prediction is what is wrong). Garbage from the dead zone never agrees with itself.
 *
 * Integer arithmetic only (the Cortex-M0+ has no FPU): angles in ticks (rw_ax12.h: 1/2560 of a register
 * unit, 0.000115 degrees, a turn = RW_AX12_TICKS_PER_TURN), speeds in ticks per millisecond Q10, time in
 * milliseconds. The dead reckoning keeps its sub-tick remainder, so a slow speed integrates without drift.
 * The public config stays in degrees; its tick values are derived when it changes. */
#ifndef RW_MULTITURN_H
#define RW_MULTITURN_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_ax12.h"

/* Consecutive readings that must agree before they are believed without a reference. */
#define RW_MULTITURN_AGREE 4u
/* How close (degrees) a reading must be to the previous one advanced by the speed to agree with it. */
#define RW_MULTITURN_AGREE_DEG 3.0f
/* The angle saturates at +-this many ticks (680 turns: +-340 m of guide travel at the shortest lead). */
#define RW_MULTITURN_MAX_TICKS (680 * RW_AX12_TICKS_PER_TURN)
/* Speeds are clamped to +-this (ticks/ms Q10): 1.4 x the fastest present-speed register value. */
#define RW_MULTITURN_MAX_SPEED_TICKS_PER_MS_Q10 (1 << 23)

typedef struct rw_multiturn_config {
    float dead_zone_margin_deg; /* readings this close to the dead zone are not trusted either */
    float max_jump_deg;         /* largest accepted difference between reading and prediction */
} rw_multiturn_config;

typedef struct rw_multiturn {
    rw_multiturn_config cfg;
    struct {
        int32_t angle_ticks;     /* continuous angle since the first valid reading, ticks */
        uint16_t angle_rem_q10;  /* sub-tick remainder of the dead reckoning, 1/1024 tick */
        bool initialized;
        bool dead_reckoning;     /* the last step was inside the dead zone band */
        uint16_t rejected;       /* readings rejected as impossible jumps (wraps) */
        uint8_t agree;           /* consecutive unreferenced readings that agree (see RW_MULTITURN_AGREE) */
        int32_t candidate_ticks; /* the latest of them, ticks in [0, RW_AX12_TICKS_VALID_RANGE] */
        int32_t turn_base_ticks; /* a whole number of turns: angle_ticks - turn_base_ticks in [0, one turn) */
        int32_t margin_ticks;    /* dead_zone_margin_deg in ticks, for the two below */
        int32_t max_jump_ticks;  /* max_jump_deg in ticks */
        float memo_margin_deg;   /* the config the tick values belong to */
        float memo_max_jump_deg;
    } state;
} rw_multiturn;

void rw_multiturn_init(rw_multiturn *m, const rw_multiturn_config *cfg);
void rw_multiturn_config_defaults(rw_multiturn_config *cfg);
void rw_multiturn_reset(rw_multiturn *m);
/* One step. valid: the servo answered; position_ticks: the register in ticks (rw_ax12_position_ticks,
 * 0..RW_AX12_TICKS_VALID_RANGE); speed_ticks_per_ms_q10: measured speed (+ = counter-clockwise,
 * rw_ax12_speed_ticks_per_ms_q10); dt_ms: time since the last step. Returns the continuous angle, ticks.
 * Discrete law: p = a[k-1] + speed * dt;  w = p mod turn
 *   w in the dead zone band [300 deg - margin, 360 deg) or [0, margin) or no reading: a[k] = p
 *   else c = p + wrap_half_turn(position - w);  |c - p| > max_jump: rejected, a[k] = p (but RW_MULTITURN_AGREE
 *   agreeing rejected readings in a row: a[k] = c, re-synchronised);  else a[k] = c */
int32_t rw_multiturn_step(rw_multiturn *m, bool valid, int32_t position_ticks, int32_t speed_ticks_per_ms_q10,
                          uint32_t dt_ms);
/* The continuous angle in degrees (for display and tests; not on the tick path). */
float rw_multiturn_angle_deg(const rw_multiturn *m);

#endif /* RW_MULTITURN_H */
