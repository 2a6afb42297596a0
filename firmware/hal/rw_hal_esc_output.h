/* ESC output: one pulse width for both ESCs (they share the command). The board drives TCC hardware PWM
 * at 400 Hz; the SIL stores the pulse for the plant. */
#ifndef RW_HAL_ESC_OUTPUT_H
#define RW_HAL_ESC_OUTPUT_H

#include <stdint.h>

typedef struct rw_hal_esc_output {
    void *ctx;
    /* Set the pulse width of both ESCs, microseconds (the core keeps it within esc_min_us..2000). */
    void (*write_pulse_us)(void *ctx, uint16_t pulse_us);
    /* Optional (NULL: the output has whole microseconds only): set the pulse at the timer's resolution, thirds
     * of a microsecond (TCC1 at 3 MHz). When set, the core calls it instead of write_pulse_us. */
    void (*write_pulse_third_us)(void *ctx, uint16_t pulse_third_us);
} rw_hal_esc_output;

#endif /* RW_HAL_ESC_OUTPUT_H */
