/* Battery ADC without Arduino's analogRead: analogRead enables the ADC, converts at the core's slow default
 * settings (prescaler 512, longest sampling) and waits, about 0.4 ms - almost half of a control tick.
 * Here the ADC is configured once and runs one conversion per tick in the background: read_mv takes the
 * finished result and starts the next, so the tick never waits.
 *
 * ADC clock: GCLK0 48 MHz (routed by the core's init) / 32 = 1.5 MHz (the SAMD21 allows up to 2.1 MHz).
 * Sampling time (SAMPLEN + 1) / 2 = 16 ADC clocks (10.7 us), enough for the divider's 8.2 kOhm source with
 * a 100 nF capacitor at the pin (docs/board.md); a conversion is about 23 us.
 * Code to volts: V_battery = code / 4096 x full_scale_mv (full scale = 3.3 V x divider ratio). */
#include "arduino_battery.h"

#include <Arduino.h>
#include <wiring_private.h>

#include "arduino_board.h"

namespace {

void adc_sync()
{
    while (ADC->STATUS.bit.SYNCBUSY) {
    }
}

uint16_t code_to_mv(const rw_arduino_battery *bat, uint32_t code)
{
    return static_cast<uint16_t>((code * bat->full_scale_mv) >> 12); /* 4095 x 65535 fits 32 bits */
}

uint16_t read_hal(void *ctx)
{
    return rw_arduino_battery_read_mv(static_cast<rw_arduino_battery *>(ctx));
}

} // namespace

void rw_arduino_battery_begin(rw_arduino_battery *bat, uint16_t full_scale_mv)
{
    bat->full_scale_mv = full_scale_mv;
    bat->last_mv = 0u;
    pinPeripheral(RW_PIN_BATTERY, PIO_ANALOG);

    ADC->CTRLA.bit.ENABLE = 0;
    adc_sync();
    ADC->CTRLB.reg = ADC_CTRLB_PRESCALER_DIV32 | ADC_CTRLB_RESSEL_12BIT;
    adc_sync();
    ADC->SAMPCTRL.reg = ADC_SAMPCTRL_SAMPLEN(31);
    ADC->REFCTRL.reg = ADC_REFCTRL_REFSEL_INTVCC1; /* VDDANA / 2 = 1.65 V */
    ADC->INPUTCTRL.reg = ADC_INPUTCTRL_MUXPOS(RW_ADC_BATTERY_AIN) | ADC_INPUTCTRL_MUXNEG_GND |
                         ADC_INPUTCTRL_GAIN_DIV2; /* x 1/2: 3.3 V at the pin is full scale */
    adc_sync();
    ADC->AVGCTRL.reg = ADC_AVGCTRL_SAMPLENUM_1;
    ADC->CTRLA.bit.ENABLE = 1;
    adc_sync();

    /* The first conversion after a configuration change is discarded, the second one kept. */
    for (int i = 0; i < 2; ++i) {
        ADC->INTFLAG.reg = ADC_INTFLAG_RESRDY;
        ADC->SWTRIG.bit.START = 1;
        while (!ADC->INTFLAG.bit.RESRDY) {
        }
        adc_sync();
        bat->last_mv = code_to_mv(bat, ADC->RESULT.reg);
    }
    ADC->SWTRIG.bit.START = 1; /* the first background conversion */
}

uint16_t rw_arduino_battery_read_mv(rw_arduino_battery *bat)
{
    if (ADC->INTFLAG.bit.RESRDY) {
        adc_sync();
        bat->last_mv = code_to_mv(bat, ADC->RESULT.reg); /* reading RESULT clears RESRDY */
        ADC->SWTRIG.bit.START = 1;
    }
    return bat->last_mv;
}

rw_hal_battery rw_arduino_battery_hal(rw_arduino_battery *bat)
{
    rw_hal_battery hal;
    hal.ctx = bat;
    hal.read_mv = read_hal;
    return hal;
}
