/*
 * rw_lowpass.h - first-order low-pass filter (time constant tau_s), single precision.
 *
 * Portable core module: no Arduino header, no heap, reads no clock (dt_s comes in).
 */
#ifndef RW_LOWPASS_H
#define RW_LOWPASS_H

#include <stdbool.h>

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
        float y;        /**< last output, input units */
        float alpha;    /**< dt / (tau + dt) for alpha_tau_s and alpha_dt_s (computed once, not per step) */
        float alpha_tau_s; /**< the tau_s alpha belongs to (0: none yet) */
        float alpha_dt_s;  /**< the dt_s alpha belongs to (0: none yet) */
    } state;            /**< private history */
} rw_lowpass;

/** Copies cfg and resets the output to 0. */
void rw_lowpass_init(rw_lowpass *f, const rw_lowpass_config *cfg);
/** Output back to 0. */
void rw_lowpass_reset(rw_lowpass *f);
/** Output set to y (for example the first measurement); a non-finite y resets to 0. */
void rw_lowpass_reset_to(rw_lowpass *f, float y);
/** Runs one sample x taken dt_s after the previous one; returns the filtered value. */
float rw_lowpass_step(rw_lowpass *f, float x, float dt_s);
/** Last output without stepping. */
float rw_lowpass_output(const rw_lowpass *f);
/** true when tau_s is finite and >= 0. */
bool rw_lowpass_config_is_valid(const rw_lowpass_config *cfg);

#ifdef __cplusplus
}
#endif

#endif /* RW_LOWPASS_H */
