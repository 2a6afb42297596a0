/* What the SIL board shows a person without a host, as the board's hal/arduino/arduino_board_report and
 * arduino_status_led do: the status LED's pattern per WiFi link state (core/rw_link_status.h, sampled once per
 * tick) and the status lines on USB (the pseudo-terminal): the link's state when it changes (NO_MODULE says the
 * module does not answer), and every SIL_REPORT_PERIOD_MS the tick's and the WiFi link's counters, one line per
 * pass. The SIL cannot time a tick in board cycles: its tick line has the ticks and overruns only. */
#ifndef SIL_BOARD_REPORT_H
#define SIL_BOARD_REPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "sil_serial.h"
#include "sil_wifi_link.h"

/* As the board's RW_REPORT_PERIOD_MS. */
#define SIL_REPORT_PERIOD_MS 10000u

typedef struct sil_board_report {
    uint8_t last_link_state;   /* last reported (0xFF: none yet) */
    uint8_t next_line;         /* periodic lines still to send in this round (one per pass) */
    uint32_t last_round_ms;
    /* the status LED (off until the first pass, as on the board) */
    bool led_on;
    uint32_t led_on_ticks;
    uint32_t led_off_ticks;
    uint32_t led_changes;
    uint32_t led_last_change_ms;
} sil_board_report;

void sil_board_report_begin(sil_board_report *r, uint32_t now_ms);
/* One background pass (after a tick): the LED, then at most one status line. */
void sil_board_report_service(sil_board_report *r, uint32_t now_ms, sil_serial *usb, const sil_wifi_link *wifi,
                              uint32_t ticks, uint32_t tick_overruns);

#endif /* SIL_BOARD_REPORT_H */
