#include "arduino_status_led.h"

#include <Arduino.h>

#include "arduino_board.h"

namespace {

bool led_on = false;

bool pattern_on(uint32_t now_ms, rw_link_state state)
{
    switch (state) {
    case RW_LINK_NOT_PROVISIONED: {
        const uint32_t t = now_ms % 2000u;
        return t < 100u || (t >= 300u && t < 400u);
    }
    case RW_LINK_NO_MODULE:
        return true;
    case RW_LINK_CONNECTING:
        return (now_ms % 200u) < 100u;
    case RW_LINK_UP:
    default:
        return (now_ms % 1000u) < 50u;
    }
}

} // namespace

void rw_arduino_status_led_begin(void)
{
    pinMode(RW_PIN_STATUS_LED, OUTPUT);
    digitalWrite(RW_PIN_STATUS_LED, LOW);
    led_on = false;
}

void rw_arduino_status_led_update(uint32_t now_ms, rw_link_state state)
{
    const bool on = pattern_on(now_ms, state);
    if (on != led_on) { /* write only on a change: digitalWrite is not free */
        digitalWrite(RW_PIN_STATUS_LED, on ? HIGH : LOW);
        led_on = on;
    }
}
