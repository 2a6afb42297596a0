/* ESC PWM on TCC1 (SAMD21 timer/counter for control), not the Servo library.
 *
 * Clock: GCLK0 (48 MHz, the Arduino core's main clock; routed here to the TCC0/TCC1 clock channel, as
 * analogWrite would) divided by 16 in TCC1 -> 3 MHz counter, 1/3 us per count, so a microsecond
 * pulse is exact (pulse_us * 3 counts). Normal PWM (NPWM), PER = 3 MHz / 400 Hz - 1 = 7499 -> 2.5 ms period.
 * WO[0] and WO[1] of TCC1 come out on PA10 (D2) and PA11 (D3) with pin function E.
 *
 * A pulse write goes to the buffered compare registers CCB0/CCB1; the TCC copies them into CC0/CC1 at the
 * next overflow (UPDATE), so a period never mixes an old and a new width. Lock update (CTRLB.LUPD) is set
 * while both CCBs are written and cleared after, so both ESCs switch in the same period.
 *
 * The core's write (rw_hal_esc_output, inside the tick; microseconds or the timer's thirds of a microsecond)
 * only stages the pulse, in counts; the tick interrupt applies it
 * first thing in the next tick (rw_arduino_esc_output_apply), so the moment the registers are written is a
 * fixed offset from the tick, whatever the previous tick did (a command, a telemetry frame): the ESC update
 * has the jitter of the interrupt's entry only, for one tick (1 ms) of added, constant delay. */
#include "arduino_esc_output.h"

#include <Arduino.h>
#include <wiring_private.h>

#include "arduino_board.h"

namespace {

const uint32_t TCC_COUNTS_PER_US = 3u; /* 48 MHz / 16 */
const uint32_t PWM_FREQUENCY_HZ = 400u;
const uint32_t PWM_PERIOD_COUNTS = 48000000u / 16u / PWM_FREQUENCY_HZ; /* 7500 */
const uint16_t ABSOLUTE_MIN_US = 900u;
const uint16_t ABSOLUTE_MAX_US = 2100u;

void tcc1_sync(uint32_t mask)
{
    while ((TCC1->SYNCBUSY.reg & mask) != 0u) {
    }
}

void stage_esc(void *ctx, uint16_t pulse_us)
{
    static_cast<rw_arduino_esc_output *>(ctx)->staged_third_us =
        static_cast<uint16_t>(static_cast<uint32_t>(pulse_us) * TCC_COUNTS_PER_US);
}

void stage_esc_third(void *ctx, uint16_t pulse_third_us)
{
    static_cast<rw_arduino_esc_output *>(ctx)->staged_third_us = pulse_third_us;
}

} // namespace

bool rw_arduino_esc_output_begin(rw_arduino_esc_output *esc, uint16_t min_us, uint16_t max_us)
{
    if (min_us < ABSOLUTE_MIN_US || max_us > ABSOLUTE_MAX_US || min_us >= max_us) {
        return false;
    }
    esc->min_us = min_us;
    esc->max_us = max_us;
    esc->pulse_us = min_us;
    esc->pulse_counts = static_cast<uint32_t>(min_us) * TCC_COUNTS_PER_US;
    esc->staged_third_us = static_cast<uint16_t>(esc->pulse_counts);
    esc->out_of_range = 0u;

    /* GCLK0 -> TCC0/TCC1 clock channel (the APB clock of TCC1 is enabled by the core's init()). */
    GCLK->CLKCTRL.reg = GCLK_CLKCTRL_CLKEN | GCLK_CLKCTRL_GEN_GCLK0 | GCLK_CLKCTRL_ID_TCC0_TCC1;
    while (GCLK->STATUS.bit.SYNCBUSY) {
    }

    TCC1->CTRLA.bit.ENABLE = 0;
    tcc1_sync(TCC_SYNCBUSY_ENABLE);
    TCC1->CTRLA.reg = TCC_CTRLA_SWRST;
    tcc1_sync(TCC_SYNCBUSY_SWRST);
    TCC1->CTRLA.reg = TCC_CTRLA_PRESCALER_DIV16 | TCC_CTRLA_PRESCSYNC_PRESC;
    TCC1->WAVE.reg = TCC_WAVE_WAVEGEN_NPWM;
    tcc1_sync(TCC_SYNCBUSY_WAVE);
    TCC1->PER.reg = PWM_PERIOD_COUNTS - 1u;
    tcc1_sync(TCC_SYNCBUSY_PER);
    TCC1->CC[0].reg = static_cast<uint32_t>(min_us) * TCC_COUNTS_PER_US;
    TCC1->CC[1].reg = static_cast<uint32_t>(min_us) * TCC_COUNTS_PER_US;
    tcc1_sync(TCC_SYNCBUSY_CC0 | TCC_SYNCBUSY_CC1);
    TCC1->CTRLA.bit.ENABLE = 1;
    tcc1_sync(TCC_SYNCBUSY_ENABLE);

    /* Only now give the pins to TCC1: the first edge the ESCs see is already a valid minimum pulse. */
    pinPeripheral(RW_PIN_ESC1, PIO_TIMER);
    pinPeripheral(RW_PIN_ESC2, PIO_TIMER);
    return true;
}

namespace {

/* Both compare registers to `counts` (TCC1 counts, 1/3 us) in the same period; skipped when they hold it already
 * (saves two synchronised register writes per tick). */
void load_counts(rw_arduino_esc_output *esc, uint32_t counts)
{
    if (counts == esc->pulse_counts) {
        return;
    }
    tcc1_sync(TCC_SYNCBUSY_CTRLB);
    TCC1->CTRLBSET.reg = TCC_CTRLBSET_LUPD;
    tcc1_sync(TCC_SYNCBUSY_CTRLB | TCC_SYNCBUSY_CCB0 | TCC_SYNCBUSY_CCB1);
    TCC1->CCB[0].reg = counts;
    TCC1->CCB[1].reg = counts;
    tcc1_sync(TCC_SYNCBUSY_CCB0 | TCC_SYNCBUSY_CCB1);
    TCC1->CTRLBCLR.reg = TCC_CTRLBCLR_LUPD;
    esc->pulse_counts = counts;
    esc->pulse_us = static_cast<uint16_t>(((counts + 1u) * 21846u) >> 16); /* / 3 rounded, no division on the M0+ */
}

} // namespace

void rw_arduino_esc_output_write_us(rw_arduino_esc_output *esc, uint16_t pulse_us)
{
    uint16_t us = pulse_us;
    if (us < esc->min_us) {
        us = esc->min_us;
        ++esc->out_of_range;
    } else if (us > esc->max_us) {
        us = esc->max_us;
        ++esc->out_of_range;
    }
    load_counts(esc, static_cast<uint32_t>(us) * TCC_COUNTS_PER_US);
}

void rw_arduino_esc_output_write_third_us(rw_arduino_esc_output *esc, uint16_t pulse_third_us)
{
    uint32_t counts = pulse_third_us; /* TCC1 counts 1/3 us: the pulse is exactly this many counts */
    const uint32_t lo = static_cast<uint32_t>(esc->min_us) * TCC_COUNTS_PER_US;
    const uint32_t hi = static_cast<uint32_t>(esc->max_us) * TCC_COUNTS_PER_US;
    if (counts < lo) {
        counts = lo;
        ++esc->out_of_range;
    } else if (counts > hi) {
        counts = hi;
        ++esc->out_of_range;
    }
    load_counts(esc, counts);
}

void rw_arduino_esc_output_apply(rw_arduino_esc_output *esc)
{
    rw_arduino_esc_output_write_third_us(esc, esc->staged_third_us);
}

rw_hal_esc_output rw_arduino_esc_output_hal(rw_arduino_esc_output *esc)
{
    rw_hal_esc_output hal;
    hal.ctx = esc;
    hal.write_pulse_us = stage_esc;
    hal.write_pulse_third_us = stage_esc_third;
    return hal;
}
