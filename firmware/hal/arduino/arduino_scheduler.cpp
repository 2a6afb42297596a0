/* 1 kHz control tick from TC3 (16-bit timer/counter), run inside its interrupt.
 *
 * Clock: GCLK0 (48 MHz) on the TCC2/TC3 clock channel, TC3 prescaler 16 -> 3 MHz; match-frequency mode
 * (MFRQ: the counter restarts at CC0) with CC0 = 3 MHz x 1 ms - 1 = 2999 -> one MC0 interrupt per
 * millisecond, locked to the crystal-trimmed 48 MHz clock. TC3 is free on this board: the core's tone() uses
 * TC5, Servo uses TC4, analogWrite uses TC3 only on pin D10 (MISO), which we never write.
 *
 * The handler runs the tick function to its end. It cannot be re-entered (an interrupt does not preempt
 * itself): a match during the tick leaves MC0 set, so the handler runs again right after, late; that is an
 * overrun (counted), as is a period skipped entirely (the tick ran over two periods: seen as a gap in the
 * tick's micros()). The latency from the period's boundary to the entry is the counter's value at the entry
 * (it restarted at the match): read with a read request, a few cycles. */
#include "arduino_scheduler.h"

#include <Arduino.h>

#include "arduino_board.h"

namespace {

const uint32_t TC_COUNTS_PER_US = 3u; /* 48 MHz / 16 */

void (*tick_fn)(void) = nullptr;
volatile rw_arduino_tick_stats stats = { 0u, 0u, 0u, 0u };
uint32_t last_entry_us = 0u;

void tc3_sync()
{
    while (TC3->COUNT16.STATUS.bit.SYNCBUSY) {
    }
}

uint16_t tc3_count()
{
    TC3->COUNT16.READREQ.reg = TC_READREQ_RREQ | TC_READREQ_ADDR(0x10); /* COUNT */
    tc3_sync();
    return TC3->COUNT16.COUNT.reg;
}

uint32_t overruns_hal(void *ctx)
{
    (void)ctx;
    return rw_arduino_scheduler_overruns();
}

} // namespace

extern "C" void TC3_Handler(void)
{
    const uint32_t latency_us = tc3_count() / TC_COUNTS_PER_US;
    TC3->COUNT16.INTFLAG.reg = TC_INTFLAG_MC0;
    const uint32_t entry_us = micros();
    if (stats.ticks != 0u && entry_us - last_entry_us >= RW_TICK_PERIOD_US + RW_TICK_PERIOD_US / 2u) {
        stats.overruns = stats.overruns + 1u; /* late or skipped */
    }
    last_entry_us = entry_us;
    if (latency_us > stats.max_latency_us) {
        stats.max_latency_us = latency_us;
    }
    if (tick_fn != nullptr) {
        tick_fn();
    }
    stats.ticks = stats.ticks + 1u;
    const uint32_t took_us = micros() - entry_us;
    if (took_us > stats.max_tick_us) {
        stats.max_tick_us = took_us;
    }
    if (TC3->COUNT16.INTFLAG.bit.MC0) {
        stats.overruns = stats.overruns + 1u; /* the next period began before this tick ended */
    }
}

void rw_arduino_scheduler_begin(void (*tick)(void))
{
    tick_fn = tick;
    NVIC_SetPriority(EIC_IRQn, RW_NVIC_PRIORITY_ENCODER);
    NVIC_SetPriority(SERCOM5_IRQn, RW_NVIC_PRIORITY_DXL_UART);
    NVIC_SetPriority(USB_IRQn, RW_NVIC_PRIORITY_USB);
    /* SysTick (millis/micros) stays at the core's 2: equal to the tick, so neither preempts the other and
     * micros() in the tick sees a pending SysTick through its PENDSTSET check. */
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
    NVIC_SetPriority(TC3_IRQn, RW_NVIC_PRIORITY_TICK);
    NVIC_EnableIRQ(TC3_IRQn);
    TC3->COUNT16.CTRLA.bit.ENABLE = 1;
    tc3_sync();
}

rw_arduino_tick_stats rw_arduino_scheduler_stats(void)
{
    rw_arduino_scheduler_mask_tick();
    rw_arduino_tick_stats copy;
    copy.ticks = stats.ticks;
    copy.overruns = stats.overruns;
    copy.max_tick_us = stats.max_tick_us;
    copy.max_latency_us = stats.max_latency_us;
    rw_arduino_scheduler_unmask_tick();
    return copy;
}

uint32_t rw_arduino_scheduler_overruns(void)
{
    return stats.overruns; /* aligned 32-bit load: atomic on the Cortex-M0+ */
}

void rw_arduino_scheduler_mask_tick(void)
{
    NVIC_DisableIRQ(TC3_IRQn);
    __DSB();
    __ISB();
}

void rw_arduino_scheduler_unmask_tick(void)
{
    NVIC_EnableIRQ(TC3_IRQn);
}

rw_hal_scheduler rw_arduino_scheduler_hal(void)
{
    rw_hal_scheduler hal;
    hal.ctx = nullptr;
    hal.tick_overruns = overruns_hal;
    return hal;
}
