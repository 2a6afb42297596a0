/* Control-tick scheduler on the board: TC3 interrupts at 1 kHz and runs the tick function in the interrupt
 * (NVIC priority RW_NVIC_PRIORITY_TICK: under the encoder and the spindle UART, over USB and the background
 * loop), so the speed loop keeps its period whatever the background loop waits on. Overruns and the tick's
 * duration are measured here. Implements rw_hal_scheduler (hal/rw_hal_scheduler.h). */
#ifndef RW_ARDUINO_SCHEDULER_H
#define RW_ARDUINO_SCHEDULER_H

#include <stdint.h>

extern "C" {
#include "rw_hal_scheduler.h"
}

/* NVIC priorities (0 = most urgent; the Cortex-M0+ has four levels), set by rw_arduino_scheduler_begin.
 * Reasoning in docs/board.md ("Interrupt priorities"). */
static const uint32_t RW_NVIC_PRIORITY_ENCODER = 0u;  /* EIC: edge time stamps, 2-3 us a handler */
static const uint32_t RW_NVIC_PRIORITY_DXL_UART = 1u; /* SERCOM5 (Serial1): 2-byte receiver, 20 us at 1 Mbps */
static const uint32_t RW_NVIC_PRIORITY_TICK = 2u;     /* TC3: the control tick, 0.1-0.5 ms */
static const uint32_t RW_NVIC_PRIORITY_USB = 3u;      /* USB: the host retries NAKed packets */

struct rw_arduino_tick_stats {
    uint32_t ticks;          /* ticks run */
    uint32_t overruns;       /* periods skipped or a tick still running when the next one was due */
    uint32_t max_tick_us;    /* longest tick, micros() from its interrupt's entry to its end */
    uint32_t max_latency_us; /* latest start, from the period's boundary (TC3 count at entry) */
};

/* Start TC3 (an interrupt every RW_TICK_PERIOD_US calling tick(now_us), now_us = micros() at its entry) and
 * set the interrupt priorities above. One scheduler per board (TC3 is a single resource). */
void rw_arduino_scheduler_begin(void (*tick)(void));

/* Copy of the statistics (read with the tick masked). */
rw_arduino_tick_stats rw_arduino_scheduler_stats(void);
/* Ticks that ran late or were skipped, since boot. */
uint32_t rw_arduino_scheduler_overruns(void);

/* Keep the tick out for a short critical section of the background loop (a few microseconds: copying what
 * the tick writes); every mask is counted in the timing model (bench/bench_tick_worst_case.py). */
void rw_arduino_scheduler_mask_tick(void);
void rw_arduino_scheduler_unmask_tick(void);

rw_hal_scheduler rw_arduino_scheduler_hal(void);

#endif /* RW_ARDUINO_SCHEDULER_H */
