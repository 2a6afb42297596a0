/* 1 kHz control tick from TC3 (16-bit timer/counter).
 *
 * Clock: GCLK0 (48 MHz) on the TCC2/TC3 clock channel, TC3 prescaler 16 -> 3 MHz; match-frequency mode
 * (MFRQ: the counter restarts at CC0) with CC0 = 3 MHz x 1 ms - 1 = 2999 -> one MC0 interrupt per
 * millisecond, locked to the crystal-trimmed 48 MHz clock, independent of how long the loop takes.
 * TC3 is free on this board: the core's tone() uses TC5, Servo uses TC4, analogWrite uses TC3 only on pin
 * D10 (MISO), which we never write.
 *
 * The interrupt only sets tick_pending. If it finds the flag still set, the loop has not even started the
 * previous tick: one period was skipped (overrun). If the loop finishes a tick and the flag is set again,
 * the tick ran past its period (overrun): the next one starts late but is not lost. */
#include "arduino_scheduler.h"

#include <Arduino.h>

#include "arduino_board.h"

namespace {

const uint32_t TC_COUNTS_PER_US = 3u; /* 48 MHz / 16 */

volatile bool tick_pending = false;
volatile uint32_t overrun_count = 0u;

void tc3_sync()
{
    while (TC3->COUNT16.STATUS.bit.SYNCBUSY) {
    }
}

uint32_t overruns_hal(void *ctx)
{
    (void)ctx;
    return rw_arduino_scheduler_overruns();
}

} // namespace

extern "C" void TC3_Handler(void)
{
    TC3->COUNT16.INTFLAG.reg = TC_INTFLAG_MC0;
    if (tick_pending) {
        overrun_count = overrun_count + 1u;
    }
    tick_pending = true;
}

void rw_arduino_scheduler_begin(void)
{
    GCLK->CLKCTRL.reg = GCLK_CLKCTRL_CLKEN | GCLK_CLKCTRL_GEN_GCLK0 | GCLK_CLKCTRL_ID_TCC2_TC3;
    while (GCLK->STATUS.bit.SYNCBUSY) {
    }
    TC3->COUNT16.CTRLA.bit.ENABLE = 0;
    tc3_sync();
    TC3->COUNT16.CTRLA.reg = TC_CTRLA_SWRST;
    while (TC3->COUNT16.CTRLA.bit.SWRST) {
    }
    TC3->COUNT16.CTRLA.reg = TC_CTRLA_MODE_COUNT16 | TC_CTRLA_WAVEGEN_MFRQ | TC_CTRLA_PRESCALER_DIV16 |
                             TC_CTRLA_PRESCSYNC_PRESC;
    tc3_sync();
    TC3->COUNT16.CC[0].reg = static_cast<uint16_t>(RW_TICK_PERIOD_US * TC_COUNTS_PER_US - 1u);
    tc3_sync();
    TC3->COUNT16.INTFLAG.reg = TC_INTFLAG_MC0;
    TC3->COUNT16.INTENSET.reg = TC_INTENSET_MC0;
    NVIC_ClearPendingIRQ(TC3_IRQn);
    NVIC_SetPriority(TC3_IRQn, 2); /* below the encoder's EIC (0, the core's default), above nothing else we own */
    NVIC_EnableIRQ(TC3_IRQn);
    TC3->COUNT16.CTRLA.bit.ENABLE = 1;
    tc3_sync();
}

bool rw_arduino_scheduler_take_tick(void)
{
    if (!tick_pending) {
        return false;
    }
    tick_pending = false; /* a single byte store: atomic against the handler */
    return true;
}

void rw_arduino_scheduler_end_tick(void)
{
    if (tick_pending) {
        noInterrupts();
        overrun_count = overrun_count + 1u;
        interrupts();
    }
}

uint32_t rw_arduino_scheduler_overruns(void)
{
    return overrun_count; /* aligned 32-bit load: atomic on the Cortex-M0+ */
}

rw_hal_scheduler rw_arduino_scheduler_hal(void)
{
    rw_hal_scheduler hal;
    hal.ctx = nullptr;
    hal.tick_overruns = overruns_hal;
    return hal;
}
