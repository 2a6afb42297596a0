/* Status LED (D6): a blink pattern per link state, so the board tells what it is doing without a host. */
#ifndef RW_ARDUINO_STATUS_LED_H
#define RW_ARDUINO_STATUS_LED_H

#include <stdint.h>

#include "arduino_link.h"

/*   not provisioned : two short flashes every 2 s
 *   no NINA module  : on
 *   connecting      : 5 Hz blink
 *   link up         : 1 Hz blink (50 ms flash)  */
void rw_arduino_status_led_begin(void);
void rw_arduino_status_led_update(uint32_t now_ms, rw_link_state state);

#endif /* RW_ARDUINO_STATUS_LED_H */
