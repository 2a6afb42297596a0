/* What the board tells a person about its WiFi link without a host: the status LED's blink pattern and the
 * line of text on USB, per link state (rw_wifi_state). One definition for the board (hal/arduino:
 * arduino_status_led, arduino_board_report) and the SIL (hal/sil: sil_board_report), so the SIL shows what the
 * board shows.
 *
 *   not provisioned : two short flashes every 2 s
 *   no NINA module  : on
 *   connecting      : 5 Hz blink
 *   link up         : 1 Hz blink (50 ms flash)
 *
 * Pure: time comes in as now_ms. */
#ifndef RW_LINK_STATUS_H
#define RW_LINK_STATUS_H

#include <stdbool.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Whether the status LED is lit at now_ms in link state (an rw_wifi_state; an unknown one blinks as UP). */
bool rw_link_status_led_on(uint32_t now_ms, uint8_t state);
/* The USB status line for link state (without the "rw: " prefix; never NULL). */
const char *rw_link_status_text(uint8_t state);

#ifdef __cplusplus
}
#endif

#endif /* RW_LINK_STATUS_H */
