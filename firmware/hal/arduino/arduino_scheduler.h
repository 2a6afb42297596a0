/* Control-tick scheduler on the board: TC3 interrupts at 1 kHz and sets a flag; the main loop runs one
 * core tick per flag. Overruns are counted. Implements rw_hal_scheduler (hal/rw_hal_scheduler.h). */
#ifndef RW_ARDUINO_SCHEDULER_H
#define RW_ARDUINO_SCHEDULER_H

#include <stdint.h>

extern "C" {
#include "rw_hal_scheduler.h"
}

/* Start TC3: an interrupt every RW_TICK_PERIOD_US. One scheduler per board (TC3 is a single resource). */
void rw_arduino_scheduler_begin(void);

/* True once per period: clears the pending tick. Call from loop(); run rw_core_tick when it returns true. */
bool rw_arduino_scheduler_take_tick(void);

/* Call after the tick's work: a tick already pending again means the work ran into the next period
 * (the next tick starts late), counted as an overrun. */
void rw_arduino_scheduler_end_tick(void);

/* Ticks that started late or were skipped, since boot. */
uint32_t rw_arduino_scheduler_overruns(void);

rw_hal_scheduler rw_arduino_scheduler_hal(void);

#endif /* RW_ARDUINO_SCHEDULER_H */
