#include "sil_nina.h"

#include <string.h>

static uint64_t ms_to_us(uint32_t ms)
{
    return ms == SIL_NINA_NEVER ? UINT64_MAX : (uint64_t)ms * 1000u;
}

void sil_nina_init(sil_nina *n, const sil_nina_faults *faults)
{
    memset(n, 0, sizeof *n);
    n->faults = *faults;
    n->ready_at_us = UINT64_MAX; /* not started until its reset */
    n->low_power = true;
    n->ap_in_reach = true;
}

static bool ap_in_reach(const sil_nina *n, uint64_t now_us)
{
    return now_us < ms_to_us(n->faults.ap_lost_at_ms) || now_us >= ms_to_us(n->faults.ap_back_at_ms);
}

void sil_nina_update(sil_nina *n, uint64_t now_us)
{
    n->ap_in_reach = ap_in_reach(n, now_us);
    if (!n->ap_in_reach) {
        if (n->associated) {
            n->associated = false;
            ++n->counters.association_losses;
        }
        n->associating = false;
        return;
    }
    if (n->joining && !n->associated && !n->associating) { /* the module joins again by itself */
        n->associating = true;
        n->associate_at_us = now_us + ms_to_us(n->faults.associate_ms);
    }
    if (n->associating && now_us >= n->associate_at_us) {
        n->associating = false;
        n->associated = true;
        ++n->counters.associations;
    }
}

bool sil_nina_ready(const sil_nina *n, uint64_t t_us)
{
    return n->reset_done && t_us >= n->ready_at_us;
}

uint64_t sil_nina_ready_at(const sil_nina *n)
{
    return n->reset_done ? n->ready_at_us : UINT64_MAX;
}

bool sil_nina_passes_datagrams(const sil_nina *n)
{
    return n->associated && n->socket_open;
}

/* A call made at t_us: counted. WiFiNINA first waits for the ready line without a time limit: the HAL checks the
 * line before its calls so that this does not happen, except where the board's HAL does not either (the boot's
 * WiFi.begin right after the first status answer); such waits are counted. The answer is back SIL_NINA_CALL_US
 * after the call starts, then the line stays busy as the slow-module fault says. */
static uint64_t call(sil_nina *n, uint64_t t_us)
{
    ++n->counters.calls;
    if (!sil_nina_ready(n, t_us)) {
        ++n->counters.calls_while_busy;
        if (n->ready_at_us != UINT64_MAX) {
            t_us = n->ready_at_us;
        }
    }
    const uint64_t done_us = t_us + SIL_NINA_CALL_US;
    const bool slow = t_us >= (uint64_t)n->faults.slow_from_ms * 1000u;
    if (n->ready_at_us != UINT64_MAX) {
        n->ready_at_us = done_us + (slow ? n->faults.busy_after_call_us : 0u);
    }
    return done_us;
}

uint64_t sil_nina_reset(sil_nina *n, uint64_t t_us)
{
    n->reset_done = true;
    n->joining = n->associating = n->associated = false;
    n->socket_open = false;
    n->low_power = true;
    const uint64_t boot_us = ms_to_us(n->faults.boot_ready_ms);
    n->ready_at_us = boot_us == UINT64_MAX ? UINT64_MAX : t_us + boot_us;
    return t_us;
}

uint64_t sil_nina_status(sil_nina *n, uint64_t t_us, bool *connected)
{
    *connected = n->associated;
    return call(n, t_us);
}

uint64_t sil_nina_begin(sil_nina *n, uint64_t t_us)
{
    n->joining = true;
    n->associated = false;
    n->associating = n->ap_in_reach;
    n->associate_at_us = t_us + ms_to_us(n->faults.associate_ms);
    const uint64_t done_us = call(n, t_us);
    if (n->associating && done_us >= n->associate_at_us) { /* no association time: joined with its answer */
        n->associating = false;
        n->associated = true;
        ++n->counters.associations;
    }
    return done_us;
}

uint64_t sil_nina_disconnect(sil_nina *n, uint64_t t_us)
{
    n->joining = n->associating = n->associated = false;
    return call(n, t_us);
}

uint64_t sil_nina_no_low_power(sil_nina *n, uint64_t t_us)
{
    n->low_power = false;
    return call(n, t_us);
}

uint64_t sil_nina_udp_begin(sil_nina *n, uint64_t t_us, bool *opened)
{
    n->socket_open = n->associated;
    *opened = n->socket_open;
    if (n->socket_open) {
        ++n->counters.sockets_opened;
    }
    return call(n, t_us);
}

uint64_t sil_nina_udp_stop(sil_nina *n, uint64_t t_us)
{
    n->socket_open = false;
    return call(n, t_us);
}
