/* Spindle: the AX-12A (wheel mode) turning the lead screw that moves the rope guide.
 *
 * Guide position from the home end: the multi-turn servo angle (rw_multiturn) times lead_mm_per_rev / 360,
 * zeroed by homing. Modes:
 *   IDLE       moving speed 0 (the servo brakes)
 *   HOMING     towards the home end at homing_speed_mmps until the limit switch closes, or the load
 *              stays over homing_load_pct with no motion for stall_time_s: position 0 there
 *   POSITION   P loop to a target: speed = clamp(kp_per_s * error, +-max_speed_mmps), 0 within
 *              tolerance_mm; stall (load over stall_load_pct, no motion, stall_time_s) -> STALL
 *   RETRACT    towards guide_max at retract_speed_mmps until the load resisting retraction stays over
 *              secure_load_pct for stall_time_s (SECURED) or the stroke ends (STROKE_END)
 * Any moving mode stops at the soft limits. No answer from the servo for timeout_s -> NO_ANSWER, IDLE. A step
 * without a reading keeps the stall/secure time held so far (it cannot see the load).
 * Call rw_spindle_step at the spindle period with the latest reading; write moving_speed_raw out. */
#ifndef RW_SPINDLE_H
#define RW_SPINDLE_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_hal_spindle.h"
#include "rw_multiturn.h"

typedef enum {
    RW_SPINDLE_IDLE = 0,
    RW_SPINDLE_HOMING,
    RW_SPINDLE_POSITION,
    RW_SPINDLE_RETRACT,
} rw_spindle_mode;

typedef enum {
    RW_SPINDLE_NOTHING = 0,
    RW_SPINDLE_HOMED_BY_STALL,
    RW_SPINDLE_HOMED_BY_SWITCH,
    RW_SPINDLE_TARGET_REACHED,
    RW_SPINDLE_SECURED,
    RW_SPINDLE_STROKE_END,
    RW_SPINDLE_STALLED,
    RW_SPINDLE_NO_ANSWER,
} rw_spindle_outcome;

typedef struct rw_spindle_config {
    float lead_mm_per_rev;
    float guide_min_mm;
    float guide_max_mm;
    float kp_per_s;
    float max_speed_mmps;
    float tolerance_mm;
    float homing_speed_mmps;
    float homing_load_pct;
    float stall_load_pct;
    float stall_time_s;
    float secure_load_pct;
    float retract_speed_mmps;
    float timeout_s;
} rw_spindle_config;

/* The config in the integer units of the step, derived when the config changes (rw_spindle_step). */
typedef struct rw_spindle_derived {
    uint32_t um_per_tick_q32;      /* guide travel per multi-turn tick, um, Q32 (lead_mm_per_rev) */
    int32_t ticks_per_ms_q10_per_umps_q8; /* guide speed (um/s) -> servo speed (ticks/ms Q10), Q8 */
    uint32_t moving_raw_per_umps_q16; /* guide speed (um/s) -> moving speed register units, Q16 */
    int32_t full_scale_umps;       /* guide speeds from this on command register value 1023 */
    int32_t kp_per_s_q16;          /* kp_per_s, Q16 */
    int32_t guide_min_um;
    int32_t guide_max_um;
    int32_t tolerance_um;
    int32_t max_speed_umps;
    int32_t homing_speed_umps;
    int32_t retract_speed_umps;
    int32_t homing_load_permille;  /* |load| >= this: over homing_load_pct */
    int32_t stall_load_permille;   /* |load| >= this: over stall_load_pct */
    int32_t secure_load_permille;  /* load >= this: over secure_load_pct */
    int32_t still_speed_raw;       /* |present speed register| under this: the guide is still (0.3 mm/s) */
} rw_spindle_derived;

typedef struct rw_spindle {
    rw_spindle_config cfg;
    struct {
        rw_multiturn turns;
        uint8_t mode;            /* rw_spindle_mode */
        bool homed;
        bool answering;
        bool target_reported;    /* TARGET_REACHED sent for the current target */
        int32_t home_ticks;      /* multi-turn angle at guide position 0 */
        int32_t position_um;     /* guide position from home, micrometres */
        float position_mm;       /* the same in millimetres, to 2^-16 mm (commands) */
        float target_mm;         /* as set by rw_spindle_move_to / rw_spindle_retract */
        int32_t target_um;       /* target_mm in micrometres (rounded) */
        uint16_t present_speed_raw; /* the last present-speed register read (stillness) */
        int32_t command_umps;    /* commanded guide speed, um/s */
        int16_t load_permille;   /* + = resisting retraction */
        uint32_t stall_ms;       /* time the stall/home condition has held */
        uint32_t silent_ms;      /* time since the last answer */
        uint16_t moving_speed_raw;
        rw_spindle_config memo_cfg; /* the config derived belongs to (all zero: none yet) */
        rw_spindle_derived derived;
    } state;
} rw_spindle;

void rw_spindle_init(rw_spindle *s, const rw_spindle_config *cfg);
/* Stop (IDLE); keeps homing and position. */
void rw_spindle_stop(rw_spindle *s);
void rw_spindle_home(rw_spindle *s);
/* Move to target_mm (the caller range-checks against guide_min_mm..guide_max_mm; kept to the micrometre). */
void rw_spindle_move_to(rw_spindle *s, float target_mm);
void rw_spindle_retract(rw_spindle *s);
/* One step: reading (NULL when the servo did not answer), elapsed time in milliseconds. Returns what happened.
 * Integer arithmetic (no soft-float on the Cortex-M0+; position_mm by bit operations from Q16.16): the
 * angle in multi-turn ticks (rw_multiturn), the guide in micrometres, speeds in um/s (the P law's
 * quantisation: 1 um of error, kp_per_s um/s of command), times in milliseconds against the float time
 * parameters compared exactly (rw_f32_ms_past). */
rw_spindle_outcome rw_spindle_step(rw_spindle *s, const rw_spindle_reading *reading, uint32_t dt_ms);

static inline bool rw_spindle_is_homed(const rw_spindle *s)
{
    return s->state.homed;
}

#endif /* RW_SPINDLE_H */
