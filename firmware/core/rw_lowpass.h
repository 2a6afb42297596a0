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
    rw_lowpass_config cfg; /**< public, may be changed between steps */
    struct {
        int64_t y_q32;     /**< last output, input units Q32 (the output: rounded to Q16.16) */
        int32_t alpha_q20; /**< dt / (tau + dt), Q20, for alpha_tau_s and alpha_dt_s (computed once, not per step) */
        float alpha_tau_s; /**< the tau_s alpha belongs to (0: none yet) */
        float alpha_dt_s;  /**< the dt_s alpha belongs to (0: none yet) */
    } state;            /**< private history */
} rw_lowpass;

/** Copies cfg and resets the output to 0. */
void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg);
/** Output back to 0. */
void rw_lowpass_reset(rw_lowpass *f);
/** Output set to y_q16 (for example the first measurement), Q16.16. */
void rw_lowpass_reset_to(rw_lowpass *f, int32_t y_q16);
/** Runs one sample x_q16 (Q16.16) taken dt_s after the previous one; returns the filtered value, Q16.16.
 *  Integer arithmetic (no soft-float on the Cortex-M0+): the state is kept to 2^-32 unit, alpha to 2^-20. */
int32_t rw_lowpass_step(rw_lowpass *f, int32_t x_q16, float dt_s);
/** Computes the coefficient for steps of dt_s now (the one float division), so that the steps that follow
 *  with this dt_s and tau_s do none: for a caller that must keep its per-step cost flat. */
void rw_lowpass_prepare(rw_lowpass *f, float dt_s);
/** Last output without stepping, Q16.16. */
int32_t rw_lowpass_output_q16(const rw_lowpass *f);
/** true when tau_s is finite and >= 0. */
bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_LOWPASS_H */
