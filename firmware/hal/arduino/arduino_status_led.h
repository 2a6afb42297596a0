/* Status LED (D6): a blink pattern per link state, so the board tells what it is doing without a host. */
#ifndef RW_ARDUINO_STATUS_LED_H
#define RW_ARDUINO_STATUS_LED_H

#include <stdint.h>

#include "arduino_link.h"

/* The pattern per link state: core/rw_link_status.h (the SIL shows the same). */
void rw_arduino_status_led_begin(void);
void rw_arduino_status_led_update(uint32_t now_ms, rw_link_state state);

#endif /* RW_ARDUINO_STATUS_LED_H */
