/* Board status lines on USB for a person at a terminal (`rw: ...`, between the protocol's frames, see
 * arduino_serial_link.h): the WiFi link's state when it changes (NO_MODULE says the module does not answer),
 * and every RW_REPORT_PERIOD_MS the counters that show the tick never waits on a bus - the tick's overruns,
 * longest tick and latest start; the WiFi calls, deferred connection steps and busy module; the spindle
 * transactions, timeouts and steps without a reading; the longest background pass. docs/board.md ("First hour
 * with the board") says how to read them. Background loop only. */
#ifndef RW_ARDUINO_BOARD_REPORT_H
#define RW_ARDUINO_BOARD_REPORT_H

#include <stdint.h>

#include "arduino_link.h"
#include "arduino_scheduler.h"
#include "arduino_serial_link.h"
#include "arduino_spindle.h"

static const uint32_t RW_REPORT_PERIOD_MS = 10000u;

struct rw_arduino_board_report {
    uint8_t last_link_state; /* rw_link_state last reported (0xFF: none yet) */
    uint8_t next_line;       /* periodic lines still to send in this round (one per pass) */
    uint32_t last_round_ms;
    uint32_t max_pass_us;    /* longest background pass (set by the caller) */
};

void rw_arduino_board_report_begin(rw_arduino_board_report *r, uint32_t now_ms);
/* One line at most per call. */
void rw_arduino_board_report_service(rw_arduino_board_report *r, uint32_t now_ms, rw_arduino_serial_link *usb,
                                     const rw_arduino_link *link, const rw_arduino_spindle *spindle);

#endif /* RW_ARDUINO_BOARD_REPORT_H */
