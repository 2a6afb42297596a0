#include "sil_board_report.h"

#include <stdio.h>

#include "rw_link_status.h"

void sil_board_report_begin(sil_board_report *r, uint32_t now_ms)
{
    r->last_link_state = 0xFFu;
    r->next_line = 0u;
    r->last_round_ms = now_ms;
    r->led_on = false;
    r->led_on_ticks = r->led_off_ticks = r->led_changes = 0u;
    r->led_last_change_ms = now_ms;
}

void sil_board_report_service(sil_board_report *r, uint32_t now_ms, sil_serial *usb, const sil_wifi_link *wifi,
                              uint32_t ticks, uint32_t tick_overruns)
{
    const uint8_t state = sil_wifi_link_state(wifi);
    const bool on = rw_link_status_led_on(now_ms, state);
    if (on != r->led_on) {
        r->led_on = on;
        ++r->led_changes;
        r->led_last_change_ms = now_ms;
    }
    if (on) {
        ++r->led_on_ticks;
    } else {
        ++r->led_off_ticks;
    }

    if (state != r->last_link_state) {
        r->last_link_state = state;
        sil_serial_note(usb, rw_link_status_text(state));
        return;
    }
    if (r->next_line == 0u && now_ms - r->last_round_ms >= SIL_REPORT_PERIOD_MS) {
        r->last_round_ms = now_ms;
        r->next_line = 2u;
    }
    if (r->next_line == 0u) {
        return;
    }
    char line[200];
    if (r->next_line == 2u) {
        snprintf(line, sizeof line, "tick ticks=%u overruns=%u max_background_pass_us=%u", (unsigned)ticks,
                 (unsigned)tick_overruns, (unsigned)wifi->counters.max_pass_us);
    } else {
        const rw_wifi_supervisor_counters *c = &wifi->supervisor.counters;
        snprintf(line, sizeof line,
                 "wifi calls=%u rx=%u tx=%u lost_rx=%u lost_tx=%u losses=%u deferred=%u module_busy=%u "
                 "ready_waits_expired=%u max_pass_us=%u",
                 (unsigned)wifi->nina.counters.calls, (unsigned)wifi->air->delivered, (unsigned)wifi->air->sent,
                 (unsigned)wifi->air->lost_rx, (unsigned)wifi->air->lost_tx, (unsigned)c->losses,
                 (unsigned)c->deferred, (unsigned)c->module_busy, (unsigned)wifi->counters.ready_waits_expired,
                 (unsigned)wifi->counters.max_pass_us);
    }
    --r->next_line;
    sil_serial_note(usb, line);
}
