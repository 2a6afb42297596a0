#include "arduino_board_report.h"

#include <string.h>

extern "C" {
#include "rw_link_status.h"
}

namespace {

/* A small text builder without printf (whole numbers only). */
struct line {
    char text[160];
    size_t len;
};

void put(line *l, const char *s)
{
    const size_t n = strlen(s);
    const size_t room = sizeof l->text - 1u - l->len;
    const size_t k = n < room ? n : room;
    memcpy(l->text + l->len, s, k);
    l->len += k;
    l->text[l->len] = '\0';
}

void put_u32(line *l, const char *name, uint32_t v)
{
    char digits[11];
    size_t n = 0u;
    do {
        digits[n++] = static_cast<char>('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    char out[12];
    out[0] = ' ';
    for (size_t i = 0u; i < n; ++i) {
        out[1u + i] = digits[n - 1u - i];
    }
    out[1u + n] = '\0';
    put(l, " ");
    put(l, name);
    put(l, out + 0);
}

} // namespace

void rw_arduino_board_report_begin(rw_arduino_board_report *r, uint32_t now_ms)
{
    r->last_link_state = 0xFFu;
    r->next_line = 0u;
    r->last_round_ms = now_ms;
    r->max_pass_us = 0u;
}

void rw_arduino_board_report_service(rw_arduino_board_report *r, uint32_t now_ms, rw_arduino_serial_link *usb,
                                     const rw_arduino_link *link, const rw_arduino_spindle *spindle)
{
    const uint8_t state = link->supervisor.state;
    if (state != r->last_link_state) {
        r->last_link_state = state;
        rw_arduino_serial_link_note(usb, rw_link_status_text(state));
        return;
    }
    if (r->next_line == 0u && now_ms - r->last_round_ms >= RW_REPORT_PERIOD_MS) {
        r->last_round_ms = now_ms;
        r->next_line = 3u;
    }
    if (r->next_line == 0u) {
        return;
    }
    line l;
    l.len = 0u;
    l.text[0] = '\0';
    if (r->next_line == 3u) {
        const rw_arduino_tick_stats t = rw_arduino_scheduler_stats();
        put(&l, "tick");
        put_u32(&l, "ticks", t.ticks);
        put_u32(&l, "overruns", t.overruns);
        put_u32(&l, "max_tick_us", t.max_tick_us);
        put_u32(&l, "max_start_us", t.max_latency_us);
        put_u32(&l, "max_background_pass_us", r->max_pass_us);
    } else if (r->next_line == 2u) {
        const rw_wifi_supervisor_counters *c = &link->supervisor.counters;
        put(&l, "wifi");
        put_u32(&l, "calls", link->calls);
        put_u32(&l, "rx", link->rx_datagrams);
        put_u32(&l, "tx", link->tx_datagrams);
        put_u32(&l, "rx_queue_full", link->rx.dropped);
        put_u32(&l, "tx_queue_full", link->tx.dropped);
        put_u32(&l, "losses", c->losses);
        put_u32(&l, "deferred", c->deferred);
        put_u32(&l, "module_busy", c->module_busy);
        put_u32(&l, "max_pass_us", link->max_service_us);
    } else {
        const rw_spindle_exchange_counters *c = &spindle->exchange.counters;
        put(&l, "spindle");
        put_u32(&l, "transactions", spindle->transactions);
        put_u32(&l, "timeouts", spindle->timeouts);
        put_u32(&l, "reads_ok", c->reads_ok);
        put_u32(&l, "steps_without_reading", c->missing);
        put_u32(&l, "late", c->late);
        put_u32(&l, "setups", spindle->setups);
        put_u32(&l, "max_transaction_us", spindle->max_transaction_us);
    }
    --r->next_line;
    rw_arduino_serial_link_note(usb, l.text);
}
