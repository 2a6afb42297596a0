/* ESC output on the board: 400 Hz hardware PWM from TCC1 on D2 and D3, both ESCs the same pulse.
 * Implements rw_hal_esc_output (hal/rw_hal_esc_output.h): the core's write stages the pulse, the next tick
 * interrupt applies it at its start (rw_arduino_esc_output_apply), a fixed point in every tick. */
#ifndef RW_ARDUINO_ESC_OUTPUT_H
#define RW_ARDUINO_ESC_OUTPUT_H

#include <stdint.h>

extern "C" {
#include "rw_hal_esc_output.h"
}

struct rw_arduino_esc_output {
    uint16_t min_us;       /* floor: no pulse under this ever reaches the ESCs (the ESC's minimum) */
    uint16_t max_us;       /* ceiling */
    uint16_t pulse_us;     /* the pulse now in the period registers (rounded to the microsecond) */
    uint32_t pulse_counts; /* the same in TCC1 counts (1/3 us) */
    volatile uint16_t staged_third_us; /* the core's latest pulse in TCC1 counts, applied at the start of the next tick */
    uint32_t out_of_range; /* requests outside [min_us, max_us] that were limited (the core never sends any) */
};

/* Start TCC1 at 400 Hz with min_us on both pins, then hand the pins to TCC1. Call once, before anything
 * can stall (the ESCs start their arming on this signal). Returns false for min_us/max_us outside
 * 900..2100 us or min_us >= max_us (and leaves the pins untouched). */
bool rw_arduino_esc_output_begin(rw_arduino_esc_output *esc, uint16_t min_us, uint16_t max_us);

/* Set both pulses, microseconds, effective from the next PWM period. */
void rw_arduino_esc_output_write_us(rw_arduino_esc_output *esc, uint16_t pulse_us);
/* The pulse in TCC1 counts (1/3 us), limited to [min_us, max_us] like write_us. */
void rw_arduino_esc_output_write_third_us(rw_arduino_esc_output *esc, uint16_t pulse_third_us);

/* Write the staged pulse (the tick interrupt's first action). */
void rw_arduino_esc_output_apply(rw_arduino_esc_output *esc);
rw_hal_esc_output rw_arduino_esc_output_hal(rw_arduino_esc_output *esc);

#endif /* RW_ARDUINO_ESC_OUTPUT_H */
