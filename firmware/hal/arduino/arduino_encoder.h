/* Rope-drive encoder on the board: edge count plus the micros() time of the latest edge, captured in the
 * external-interrupt handler of D7. Implements rw_hal_encoder (hal/rw_hal_encoder.h). */
#ifndef RW_ARDUINO_ENCODER_H
#define RW_ARDUINO_ENCODER_H

#include <stdint.h>

extern "C" {
#include "rw_hal_encoder.h"
}

struct rw_arduino_encoder {
    rw_encoder_sample latched; /* the snapshot read() returns, taken by rw_arduino_encoder_latch */
};

/* Attach the interrupt (rising edges of RW_PIN_ENCODER, input with pull-up). One encoder per board. */
void rw_arduino_encoder_begin(rw_arduino_encoder *enc);

/* Snapshot count and last-edge time together with the tick time, interrupts masked for a few cycles;
 * returns that tick time (micros()). Call at the start of every control tick and pass the result to
 * rw_core_tick, so the last edge can never be later than the tick time. */
uint32_t rw_arduino_encoder_latch(rw_arduino_encoder *enc);

rw_hal_encoder rw_arduino_encoder_hal(rw_arduino_encoder *enc);

#endif /* RW_ARDUINO_ENCODER_H */
