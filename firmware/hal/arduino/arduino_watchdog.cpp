/* Watchdog: Adafruit SleepyDog configures the SAMD21 WDT and reads the reset cause; feeding is done here.
 *
 * Why SleepyDog: it is maintained by Adafruit for the SAMD21 (Feather M0, Arduino Zero, MKR), and its
 * enable() does the fiddly part - the 1.024 kHz WDT clock from the ultra-low-power 32 kHz oscillator on
 * GCLK2 (a generator the Arduino core leaves free), the period bits, the synchronised enable.
 * Why not its reset() for feeding: it busy-waits on WDT SYNCBUSY before writing CLEAR, and after a CLEAR
 * the WDT stays busy for several cycles of its 1 kHz clock. Fed every 1 ms control tick, reset() would
 * stall the loop for milliseconds. Here the feed writes CLEAR only when SYNCBUSY is low and otherwise
 * skips: with a 250 ms period and a feed attempt every tick, a skipped feed is harmless (Zephyr's SAM0
 * watchdog driver checks SYNCBUSY before CLEAR for the same reason). */
#include "arduino_watchdog.h"

#include <Adafruit_SleepyDog.h>
#include <Arduino.h>

uint8_t rw_arduino_watchdog_reset_cause(void)
{
    return Watchdog.resetCause();
}

uint32_t rw_arduino_watchdog_begin(uint32_t period_ms)
{
    const int clamped = period_ms > 16000u ? 16000 : static_cast<int>(period_ms);
    return static_cast<uint32_t>(Watchdog.enable(clamped));
}

bool rw_arduino_watchdog_feed(void)
{
    if (WDT->STATUS.bit.SYNCBUSY) {
        return false;
    }
    WDT->CLEAR.reg = WDT_CLEAR_CLEAR_KEY;
    return true;
}

void rw_arduino_watchdog_feed_callback(void)
{
    (void)rw_arduino_watchdog_feed();
}
