#include "arduino_status_led.h"

#include <Arduino.h>

#include "arduino_board.h"

extern "C" {
#include "rw_link_status.h"
}

namespace {

bool led_on = false;

} // namespace

void rw_arduino_status_led_begin(void)
{
    pinMode(RW_PIN_STATUS_LED, OUTPUT);
    digitalWrite(RW_PIN_STATUS_LED, LOW);
    led_on = false;
}

void rw_arduino_status_led_update(uint32_t now_ms, rw_link_state state)
{
    const bool on = rw_link_status_led_on(now_ms, static_cast<uint8_t>(state));
    if (on != led_on) { /* write only on a change: digitalWrite is not free */
        digitalWrite(RW_PIN_STATUS_LED, on ? HIGH : LOW);
        led_on = on;
    }
}
