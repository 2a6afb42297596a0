#include "rw_wifi_supervisor.h"

#include <string.h>

void rw_wifi_supervisor_config_defaults(rw_wifi_supervisor_config *cfg)
{
    cfg->status_poll_ms = 500u;
    cfg->reconnect_interval_ms = 5000u;
    cfg->module_hung_ms = 1000u;
}

void rw_wifi_supervisor_init(rw_wifi_supervisor *s, const rw_wifi_supervisor_config *cfg, rw_wifi_state state,
                             uint32_t now_ms)
{
    memset(s, 0, sizeof *s);
    s->cfg = *cfg;
    s->state = (uint8_t)state;
    s->associated = state == RW_WIFI_UP;
    s->last_poll_ms = now_ms;
    s->last_attempt_ms = now_ms;
}

void rw_wifi_supervisor_restart(rw_wifi_supervisor *s, bool provisioned, uint32_t now_ms)
{
    if (s->state == RW_WIFI_NO_MODULE) {
        return;
    }
    s->state = provisioned ? RW_WIFI_CONNECTING : RW_WIFI_NOT_PROVISIONED;
    s->associated = false;
    s->close_pending = false;
    s->deferring = false;
    s->last_poll_ms = now_ms;
    s->last_attempt_ms = now_ms;
    if (provisioned) {
        ++s->counters.attempts;
    }
}

/* A connection step wanted now: taken when the rope is down, else deferred (counted once per deferral). */
static bool may_step(rw_wifi_supervisor *s, bool rope_down)
{
    if (rope_down) {
        s->deferring = false;
        return true;
    }
    if (!s->deferring) {
        s->deferring = true;
        ++s->counters.deferred;
    }
    return false;
}

rw_wifi_action rw_wifi_supervisor_step(rw_wifi_supervisor *s, uint32_t now_ms, bool module_ready, bool rope_down)
{
    if (s->state == RW_WIFI_NOT_PROVISIONED || s->state == RW_WIFI_NO_MODULE) {
        return RW_WIFI_DO_NOTHING;
    }
    if (!module_ready) {
        if (!s->busy) {
            s->busy = true;
            s->busy_since_ms = now_ms;
        }
        ++s->counters.module_busy;
        if (now_ms - s->busy_since_ms >= s->cfg.module_hung_ms) {
            s->state = RW_WIFI_NO_MODULE;
            ++s->counters.module_hangs;
        }
        return RW_WIFI_DO_NOTHING;
    }
    s->busy = false;
    if (s->close_pending) {
        s->close_pending = false;
        return RW_WIFI_DO_CLOSE_SOCKET;
    }
    if (now_ms - s->last_poll_ms >= s->cfg.status_poll_ms) {
        s->last_poll_ms = now_ms;
        ++s->counters.polls;
        return RW_WIFI_DO_POLL_STATUS;
    }
    if (s->state == RW_WIFI_UP) {
        return RW_WIFI_DO_IO;
    }
    /* CONNECTING */
    if (s->associated) {
        return may_step(s, rope_down) ? RW_WIFI_DO_OPEN_SOCKET : RW_WIFI_DO_NOTHING;
    }
    if (now_ms - s->last_attempt_ms >= s->cfg.reconnect_interval_ms) {
        if (!may_step(s, rope_down)) {
            return RW_WIFI_DO_NOTHING;
        }
        s->last_attempt_ms = now_ms;
        ++s->counters.attempts;
        return RW_WIFI_DO_START_CONNECT;
    }
    return RW_WIFI_DO_NOTHING;
}

void rw_wifi_supervisor_status(rw_wifi_supervisor *s, uint32_t now_ms, bool connected)
{
    if (s->state == RW_WIFI_UP) {
        if (!connected) {
            s->state = RW_WIFI_CONNECTING;
            s->associated = false;
            s->close_pending = true;
            ++s->counters.losses;
            s->last_attempt_ms = now_ms - s->cfg.reconnect_interval_ms; /* a new connection may start at once */
        }
        return;
    }
    if (s->state == RW_WIFI_CONNECTING) {
        s->associated = connected;
    }
}

void rw_wifi_supervisor_socket(rw_wifi_supervisor *s, bool opened)
{
    if (s->state != RW_WIFI_CONNECTING) {
        return;
    }
    if (opened) {
        s->state = RW_WIFI_UP;
        s->deferring = false;
        ++s->counters.connects;
    } else {
        s->associated = false; /* poll again, then retry */
    }
}
