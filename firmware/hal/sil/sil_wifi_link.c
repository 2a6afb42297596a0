#include "sil_wifi_link.h"

#include <string.h>

void sil_wifi_link_init(sil_wifi_link *link, const sil_nina_faults *faults, sil_link *air)
{
    memset(link, 0, sizeof *link);
    sil_nina_init(&link->nina, faults);
    link->air = air;
    link->boot_phase = SIL_WIFI_BOOT_START;
    air->open = false;
}

void sil_wifi_link_update(sil_wifi_link *link, uint64_t now_us)
{
    sil_nina_update(&link->nina, now_us);
    /* the board moves datagrams only while its policy says UP (RW_WIFI_DO_IO): never while connecting or with
     * no module, whatever the module itself still holds */
    const bool open = link->boot_phase == SIL_WIFI_BOOT_DONE && link->supervisor.state == RW_WIFI_UP &&
                      sil_nina_passes_datagrams(&link->nina);
    if (!open && link->air->open) {
        link->air->lost_rx += link->air->count; /* the module's socket closed with them */
        link->air->count = 0u;
    }
    link->air->open = open;
}

/* The ready line within RW_WIFI_CALL_READY_WAIT_US of *t_us (the wait moves *t_us); false when it runs out. */
static bool ready_soon(sil_wifi_link *link, uint64_t *t_us)
{
    if (sil_nina_ready(&link->nina, *t_us)) {
        return true;
    }
    const uint64_t at_us = sil_nina_ready_at(&link->nina);
    if (at_us != UINT64_MAX && at_us - *t_us <= RW_WIFI_CALL_READY_WAIT_US) {
        *t_us = at_us;
        return true;
    }
    *t_us += RW_WIFI_CALL_READY_WAIT_US;
    ++link->counters.ready_waits_expired;
    return false;
}

/* noLowPowerMode + udp.begin, each after the ready line (bounded). */
static bool open_socket(sil_wifi_link *link, uint64_t *t_us)
{
    if (!ready_soon(link, t_us)) {
        return false;
    }
    *t_us = sil_nina_no_low_power(&link->nina, *t_us);
    if (!ready_soon(link, t_us)) {
        return false;
    }
    bool opened = false;
    *t_us = sil_nina_udp_begin(&link->nina, *t_us, &opened);
    return opened;
}

static void boot_done(sil_wifi_link *link, uint64_t now_us, rw_wifi_state reached)
{
    rw_wifi_supervisor_config cfg;
    rw_wifi_supervisor_config_defaults(&cfg);
    rw_wifi_supervisor_init(&link->supervisor, &cfg, reached, (uint32_t)(now_us / 1000u));
    if (reached == RW_WIFI_UP) {
        ++link->supervisor.counters.connects;
    }
    link->boot_phase = SIL_WIFI_BOOT_DONE;
    link->counters.boot_ms = (uint32_t)((now_us - link->boot_start_us) / 1000u);
    link->busy_until_us = now_us;
}

/* After WiFi.begin returned: its status, then the socket (as arduino_link.cpp's boot_connect). */
static void boot_finish(sil_wifi_link *link, uint64_t t_us)
{
    bool connected = false;
    if (ready_soon(link, &t_us)) {
        t_us = sil_nina_status(&link->nina, t_us, &connected);
    }
    if (!connected) {
        boot_done(link, t_us, RW_WIFI_CONNECTING);
        return;
    }
    const bool opened = open_socket(link, &t_us);
    boot_done(link, t_us, opened ? RW_WIFI_UP : RW_WIFI_CONNECTING);
}

bool sil_wifi_link_boot_step(sil_wifi_link *link, uint64_t now_us)
{
    if (link->boot_phase == SIL_WIFI_BOOT_START) { /* WiFiDrv::wifiDriverInit: the module's reset */
        link->boot_start_us = now_us;
        (void)sil_nina_reset(&link->nina, now_us);
        link->boot_phase = SIL_WIFI_BOOT_WAIT_READY; /* its line may already be up */
    }
    switch (link->boot_phase) {
    case SIL_WIFI_BOOT_WAIT_READY: {
        uint64_t t_us = now_us;
        if (!sil_nina_ready(&link->nina, t_us)) {
            const uint64_t at_us = sil_nina_ready_at(&link->nina);
            const uint64_t limit_us = link->boot_start_us + (uint64_t)RW_WIFI_BOOT_READY_MS * 1000u;
            if (at_us <= limit_us && at_us <= now_us) {
                t_us = at_us;
            } else {
                if (now_us >= limit_us) {
                    boot_done(link, limit_us, RW_WIFI_NO_MODULE); /* no call: each would wait for ever */
                    return true;
                }
                return false;
            }
        }
        bool connected = false;
        t_us = sil_nina_status(&link->nina, t_us, &connected); /* the first answer: the module is there */
        /* SIL: the loopback network is joined whatever the SSID (the board stops at NOT_PROVISIONED without one) */
        t_us = sil_nina_begin(&link->nina, t_us);
        link->join_start_us = t_us;
        link->boot_phase = SIL_WIFI_BOOT_JOINING;
        if (!link->nina.associated) {
            return false;
        }
        boot_finish(link, t_us);
        return true;
    }
    case SIL_WIFI_BOOT_JOINING:
        if (!link->nina.associated &&
            now_us - link->join_start_us < (uint64_t)RW_WIFI_BOOT_CONNECT_TIMEOUT_MS * 1000u) {
            return false; /* WiFi.begin still waiting (its status polls) */
        }
        boot_finish(link, now_us);
        return true;
    case SIL_WIFI_BOOT_START:
    case SIL_WIFI_BOOT_DONE:
    default:
        return true;
    }
}

/* Copy the record's credentials (always NUL-terminated); true if they differ from those in use. */
static bool take_credentials(sil_wifi_link *link, const rw_config *config)
{
    return rw_config_take_credentials(config, link->ssid, link->password);
}

void sil_wifi_link_take_credentials(sil_wifi_link *link, const rw_config *config)
{
    (void)take_credentials(link, config);
}

void sil_wifi_link_reconfigure(sil_wifi_link *link, uint64_t now_us, const rw_config *config)
{
    if (!take_credentials(link, config) || link->boot_phase != SIL_WIFI_BOOT_DONE ||
        link->supervisor.state == RW_WIFI_NO_MODULE) {
        return;
    }
    uint64_t t_us = now_us > link->busy_until_us ? now_us : link->busy_until_us;
    const bool ready = ready_soon(link, &t_us);
    if (ready && link->supervisor.state == RW_WIFI_UP) {
        t_us = sil_nina_udp_stop(&link->nina, t_us);
    }
    if (ready && ready_soon(link, &t_us)) {
        t_us = sil_nina_disconnect(&link->nina, t_us);
    }
    /* SIL: joined whatever the SSID, so always "provisioned" */
    rw_wifi_supervisor_restart(&link->supervisor, true, (uint32_t)(now_us / 1000u));
    if (ready && ready_soon(link, &t_us)) {
        t_us = sil_nina_begin(&link->nina, t_us);
    }
    link->busy_until_us = t_us;
}

void sil_wifi_link_service(sil_wifi_link *link, uint64_t now_us, bool rope_down)
{
    if (link->boot_phase != SIL_WIFI_BOOT_DONE) {
        return;
    }
    if (now_us < link->busy_until_us) {
        ++link->counters.passes_skipped; /* the previous pass is still waiting on the module */
        return;
    }
    ++link->counters.passes;
    uint64_t t_us = now_us;
    const uint32_t now_ms = (uint32_t)(now_us / 1000u);
    rw_wifi_supervisor *sup = &link->supervisor;
    switch (rw_wifi_supervisor_step(sup, now_ms, sil_nina_ready(&link->nina, t_us), rope_down)) {
    case RW_WIFI_DO_POLL_STATUS: {
        bool connected = false;
        t_us = sil_nina_status(&link->nina, t_us, &connected);
        rw_wifi_supervisor_status(sup, now_ms, connected);
        break;
    }
    case RW_WIFI_DO_START_CONNECT:
        t_us = sil_nina_begin(&link->nina, t_us);
        break;
    case RW_WIFI_DO_OPEN_SOCKET: {
        const bool opened = open_socket(link, &t_us);
        rw_wifi_supervisor_socket(sup, opened);
        break;
    }
    case RW_WIFI_DO_CLOSE_SOCKET:
        t_us = sil_nina_udp_stop(&link->nina, t_us);
        break;
    case RW_WIFI_DO_IO:      /* datagrams move through the socket directly (sil_link.h) */
    case RW_WIFI_DO_NOTHING:
    default:
        break;
    }
    const uint64_t took_us = t_us - now_us;
    if (took_us > link->counters.max_pass_us) {
        link->counters.max_pass_us = (uint32_t)took_us;
    }
    link->busy_until_us = t_us;
    /* the socket may have opened or closed: datagrams pass from the next tick (sil_wifi_link_update) */
}
