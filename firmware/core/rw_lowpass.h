/*
 * rw_lowpass.h - first-order low-pass filter (time constant tau_s), Q16.16 fixed point in and out.
 *
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_LOWPASS_H
#define RW_LOWPASS_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Public configuration. */
typedef struct rw_lowpass_config {
    float tau_s; /**< time constant, seconds; 0 (or any non-positive/non-finite value) = pass-through */
} rw_lowpass_config;

typedef struct rw_lowpass {
    rw_lowpass_config cfg; /**< public; after a change call rw_lowpass_prepare */
    struct {
        int64_t y_q32;       /**< last output, input units Q32 (the output: rounded to Q16.16) */
        int32_t alpha_q20;   /**< dt / (tau + dt) for cfg.tau_s and prepared_dt_s, Q20 (rw_lowpass_prepare) */
        float prepared_dt_s; /**< the step alpha_q20 is for (0: none; every step then computes its own) */
    } state;              /**< private: history and the prepared coefficient */
} rw_lowpass;

/** Copies cfg, prepares for no step in particular (rw_lowpass_prepare) and resets the output to 0. */
void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg);
/** Output back to 0. */
void rw_lowpass_reset(rw_lowpass *f);
/** Output set to y_q16 (for example the first measurement), Q16.16. */
void rw_lowpass_reset_to(rw_lowpass *f, int32_t y_q16);
/** Runs one sample x_q16 (Q16.16) taken dt_s after the previous one; returns the filtered value, Q16.16.
 *  Integer arithmetic (no soft-float on the Cortex-M0+): the state is kept to 2^-32 unit, alpha to 2^-20. */
int32_t rw_lowpass_step(rw_lowpass *f, int32_t x_q16, float dt_s);
/** Converts the configuration for steps of dt_s (the one float division): call it after changing cfg (the
 *  core does, from rw_core_apply_params). A step of that dt_s then costs integer arithmetic only; a step of
 *  another dt_s computes its coefficient itself (same result, a division each time). dt_s <= 0 or not
 *  finite prepares for no step in particular. */
void rw_lowpass_prepare(rw_lowpass *f, float dt_s);
/** Last output without stepping, Q16.16. */
int32_t rw_lowpass_output_q16(const rw_lowpass *f);
/** true when tau_s is finite and >= 0. */
bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_LOWPASS_H */
