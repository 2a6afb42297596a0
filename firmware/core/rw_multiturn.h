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
 * with each other: the prediction is what is wrong). Garbage from the dead zone never agrees with itself. */
#ifndef RW_MULTITURN_H
#define RW_MULTITURN_H

#include <stdbool.h>
#include <stdint.h>

/* Consecutive readings that must agree before they are believed without a reference. */
#define RW_MULTITURN_AGREE 4u
/* How close (degrees) a reading must be to the previous one advanced by the speed to agree with it. */
#define RW_MULTITURN_AGREE_DEG 3.0f

typedef struct rw_multiturn_config {
    float dead_zone_margin_deg; /* readings this close to the dead zone are not trusted either */
    float max_jump_deg;         /* largest accepted difference between reading and prediction */
} rw_multiturn_config;

typedef struct rw_multiturn {
    rw_multiturn_config cfg;
    struct {
        float angle_deg; /* continuous angle since the first valid reading, degrees */
        bool initialized;
        bool dead_reckoning; /* the last step was inside the dead zone band */
        uint16_t rejected;   /* readings rejected as impossible jumps (wraps) */
        uint8_t agree;       /* consecutive unreferenced readings that agree (see RW_MULTITURN_AGREE) */
        float candidate_deg; /* the latest of them, degrees in [0, 360) */
    } state;
} rw_multiturn;

void rw_multiturn_init(rw_multiturn *m, const rw_multiturn_config *cfg);
void rw_multiturn_config_defaults(rw_multiturn_config *cfg);
void rw_multiturn_reset(rw_multiturn *m);
/* One step. valid: the servo answered; position_deg: the register in degrees [0, 300];
 * speed_deg_s: measured speed (+ = counter-clockwise); returns the continuous angle in degrees.
 * Discrete law: p = a[k-1] + speed * dt;  w = p mod 360
 *   w in the dead zone band [300 - margin, 360) or [0, margin) or no reading: a[k] = p
 *   else c = p + wrap180(position_deg - w);  |c - p| > max_jump: rejected, a[k] = p (but RW_MULTITURN_AGREE
 *   agreeing rejected readings in a row: a[k] = c, re-synchronised);  else a[k] = c */
float rw_multiturn_step(rw_multiturn *m, bool valid, float position_deg, float speed_deg_s, float dt_s);

#endif /* RW_MULTITURN_H */
