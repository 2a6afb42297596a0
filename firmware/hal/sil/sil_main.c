/* rw_sil: the firmware core with the sil HAL, as its own process.
 *
 *   rw_sil [--cmd-port N] [--plant-port N] [--plant-timeout-s S] [--tick-us N] [--state-file PATH]
 *          [--spindle-bus-us N] [--wifi-boot-ready-ms N|never] [--wifi-associate-ms N]
 *          [--wifi-ap-lost-ms N --wifi-ap-back-ms N|never] [--wifi-busy-us N] [--wifi-slow-from-ms N]
 *
 * Binds the command link (the host's UDP port, as the board's WiFi) and the plant port on 127.0.0.1
 * (0 = any free port), opens a pseudo-terminal as the board's USB serial (provisioning), prints
 * "rw_sil ready cmd_port=N plant_port=N serial=PATH" on stdout, then runs one core tick per SIL_SENSORS
 * datagram from the plant. --state-file is the board's flash (configuration record: key, parameters,
 * boot counter = session id); without it nothing persists and nothing can be committed.
 * --spindle-bus-us is the bus time of one spindle transaction (sil_spindle_bus.h, default 350). A
 * PROVISION_COMMIT's write to the state file is done between ticks, SIL_CONFIG_STORE_DEFAULT_SAVE_TICKS after
 * its request (sil_config_store.h). The WiFi link is the NINA module model driven as on the board
 * (sil_wifi_link.h, sil_nina.h): --wifi-* script its faults (a module whose ready line rises N ms after its reset,
 * or never: boot reaches NO_MODULE; association time; the access point out of reach from --wifi-ap-lost-ms until
 * --wifi-ap-back-ms of plant time; the ready line busy --wifi-busy-us after each call from --wifi-slow-from-ms on).
 * Until the WiFi boot is done the control tick does not run and the ESCs hold the bottom pulse (as in the board's
 * setup()). The status LED and the USB status lines are the board's (sil_board_report.h). On exit it prints the
 * spindle bus counters
 * ("rw_sil spindle_bus requests=N ..."), the flash counters ("rw_sil flash requests=N ..."), the WiFi link's
 * ("rw_sil wifi state=NAME ...") and the status LED's ("rw_sil led ...") on stderr. Exits 0 on SIGINT/SIGTERM, 3 when the plant has been silent
 * for --plant-timeout-s (never hangs), 2 on bad arguments or sockets. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rw_core.h"
#include "rw_defaults.h"
#include "sil_board_report.h"
#include "sil_config_store.h"
#include "sil_link.h"
#include "sil_lockstep.h"
#include "sil_serial.h"
#include "sil_spindle_bus.h"
#include "sil_wifi_link.h"

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

/* The sil scheduler: the plant owns the clock, so a tick is late when the plant's time jumped by more than
 * one period (the plant skipped ticks, as a stalled main loop would); each missed period counts once. */
typedef struct sil_scheduler {
    uint32_t tick_us;
    uint32_t last_time_us;
    uint32_t overruns;
    int started;
} sil_scheduler;

static void sil_scheduler_on_tick(sil_scheduler *s, uint32_t time_us)
{
    uint32_t dt = time_us - s->last_time_us;
    if (s->started && dt > s->tick_us + s->tick_us / 2u) {
        s->overruns += (dt - s->tick_us / 2u) / s->tick_us;
    }
    s->last_time_us = time_us;
    s->started = 1;
}

static uint32_t tick_overruns(void *ctx)
{
    const sil_scheduler *s = ctx;
    return s->overruns;
}

static int parse_uint(const char *text, long max, long *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || v < 0 || v > max) {
        return 0;
    }
    *out = v;
    return 1;
}

static int usage(const char *msg)
{
    fprintf(stderr,
            "rw_sil: %s\nusage: rw_sil [--cmd-port N] [--plant-port N] [--plant-timeout-s S] [--tick-us N] "
            "[--state-file PATH] [--spindle-bus-us N] [--wifi-boot-ready-ms N|never] [--wifi-associate-ms N] "
            "[--wifi-ap-lost-ms N --wifi-ap-back-ms N|never] [--wifi-busy-us N] [--wifi-slow-from-ms N]\n",
            msg);
    return 2;
}

/* States that drive the rope (as the board's main.cpp): WiFi connection steps wait for the others. */
static bool rope_down(uint8_t state)
{
    return state != RW_STATE_SPINUP && state != RW_STATE_AIRBORNE && state != RW_STATE_SPINDOWN &&
           state != RW_STATE_RELAX;
}

static const char *wifi_state_name(uint8_t state)
{
    switch (state) {
    case RW_WIFI_NOT_PROVISIONED:
        return "NOT_PROVISIONED";
    case RW_WIFI_NO_MODULE:
        return "NO_MODULE";
    case RW_WIFI_CONNECTING:
        return "CONNECTING";
    case RW_WIFI_UP:
        return "UP";
    default:
        return "?";
    }
}

/* A fault time in ms, or "never". */
static int parse_ms_or_never(const char *text, uint32_t *out)
{
    long v = 0;
    if (strcmp(text, "never") == 0) {
        *out = SIL_NINA_NEVER;
        return 1;
    }
    if (!parse_uint(text, 86400000L, &v)) {
        return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

int main(int argc, char **argv)
{
    long cmd_port = 14550, plant_port = 14560, plant_timeout_s = 10, tick_us = 1000;
    long spindle_bus_us = SIL_SPINDLE_BUS_DEFAULT_TRANSACTION_US;
    static sil_config_store store = { .save_ticks = SIL_CONFIG_STORE_DEFAULT_SAVE_TICKS };
    sil_nina_faults wifi_faults = { .boot_ready_ms = 0u, .associate_ms = 0u, .ap_lost_at_ms = SIL_NINA_NEVER,
                                    .ap_back_at_ms = SIL_NINA_NEVER, .busy_after_call_us = 0u, .slow_from_ms = 0u };
    bool ap_back_given = false;
    for (int i = 1; i < argc; ++i) {
        long *target = NULL;
        long max = 65535;
        uint32_t *wifi_target = NULL;
        int wifi_never_ok = 0;
        if (strcmp(argv[i], "--wifi-boot-ready-ms") == 0) {
            wifi_target = &wifi_faults.boot_ready_ms;
            wifi_never_ok = 1;
        } else if (strcmp(argv[i], "--wifi-associate-ms") == 0) {
            wifi_target = &wifi_faults.associate_ms;
        } else if (strcmp(argv[i], "--wifi-ap-lost-ms") == 0) {
            wifi_target = &wifi_faults.ap_lost_at_ms;
        } else if (strcmp(argv[i], "--wifi-ap-back-ms") == 0) {
            wifi_target = &wifi_faults.ap_back_at_ms;
            wifi_never_ok = 1;
            ap_back_given = true;
        } else if (strcmp(argv[i], "--wifi-busy-us") == 0) {
            wifi_target = &wifi_faults.busy_after_call_us;
        } else if (strcmp(argv[i], "--wifi-slow-from-ms") == 0) {
            wifi_target = &wifi_faults.slow_from_ms;
        }
        if (wifi_target != NULL) {
            if (i + 1 >= argc || !parse_ms_or_never(argv[i + 1], wifi_target) ||
                (!wifi_never_ok && *wifi_target == SIL_NINA_NEVER)) {
                return usage(wifi_never_ok ? "option needs a whole number 0..86400000 or never"
                                           : "option needs a whole number 0..86400000");
            }
            ++i;
            continue;
        }
        if (strcmp(argv[i], "--state-file") == 0) {
            if (i + 1 >= argc || strlen(argv[i + 1]) >= sizeof store.path) {
                return usage("--state-file needs a path");
            }
            strcpy(store.path, argv[++i]);
            continue;
        }
        if (strcmp(argv[i], "--cmd-port") == 0) {
            target = &cmd_port;
        } else if (strcmp(argv[i], "--plant-port") == 0) {
            target = &plant_port;
        } else if (strcmp(argv[i], "--plant-timeout-s") == 0) {
            target = &plant_timeout_s;
            max = 3600;
        } else if (strcmp(argv[i], "--spindle-bus-us") == 0) {
            target = &spindle_bus_us;
            max = 1000000;
        } else if (strcmp(argv[i], "--tick-us") == 0) {
            target = &tick_us;
            max = 100000;
        } else {
            return usage("unknown argument");
        }
        if (i + 1 >= argc || !parse_uint(argv[i + 1], max, target)) {
            return usage("option needs a whole number in range");
        }
        ++i;
    }

    if (ap_back_given && wifi_faults.ap_lost_at_ms == SIL_NINA_NEVER) {
        return usage("--wifi-ap-back-ms needs --wifi-ap-lost-ms");
    }
    if (wifi_faults.ap_back_at_ms != SIL_NINA_NEVER && wifi_faults.ap_back_at_ms <= wifi_faults.ap_lost_at_ms) {
        return usage("--wifi-ap-back-ms must be later than --wifi-ap-lost-ms");
    }

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    static sil_link link;
    static sil_lockstep lockstep;
    if (!sil_link_open(&link, (uint16_t)cmd_port)) {
        fprintf(stderr, "rw_sil: cannot bind command port 127.0.0.1:%ld: %s\n", cmd_port, strerror(errno));
        return 2;
    }
    if (!sil_lockstep_open(&lockstep, (uint16_t)plant_port)) {
        fprintf(stderr, "rw_sil: cannot bind plant port 127.0.0.1:%ld: %s\n", plant_port, strerror(errno));
        return 2;
    }

    static sil_serial serial;
    if (!sil_serial_open(&serial)) {
        fprintf(stderr, "rw_sil: cannot open a pseudo-terminal for the serial link: %s\n", strerror(errno));
        return 2;
    }
    rw_hal_link serial_hal = sil_serial_hal(&serial);
    rw_hal_config_store store_hal = sil_config_store_hal(&store);
    rw_hal_link link_hal = sil_link_hal(&link);
    rw_hal_encoder encoder_hal = sil_lockstep_encoder(&lockstep);
    rw_hal_battery battery_hal = sil_lockstep_battery(&lockstep);
    rw_hal_esc_output esc_hal = sil_lockstep_esc(&lockstep);
    static sil_scheduler scheduler = { 0 };
    scheduler.tick_us = tick_us > 0 ? (uint32_t)tick_us : 1000u;
    rw_hal_scheduler scheduler_hal = { .ctx = &scheduler, .tick_overruns = tick_overruns };
    static sil_spindle_bus spindle_bus;
    sil_spindle_bus_init(&spindle_bus, spindle_bus_us > 0 ? (uint32_t)spindle_bus_us : 1u, scheduler.tick_us);
    rw_hal_spindle spindle_hal = sil_spindle_bus_hal(&spindle_bus);
    rw_hal hal = {
        .esc = &esc_hal, .encoder = &encoder_hal, .battery = &battery_hal, .link = &link_hal, .scheduler = &scheduler_hal,
        .spindle = &spindle_hal, .serial = &serial_hal, .config = store.path[0] != '\0' ? &store_hal : NULL,
    };
    static rw_core core;
    rw_core_init(&core);
    static sil_wifi_link wifi;
    sil_wifi_link_init(&wifi, &wifi_faults, &link);
    static sil_board_report report;
    bool booted = false;       /* the WiFi boot is done: the control tick runs */
    bool first_tick = true;
    uint32_t link_commits = 0u;
    uint32_t ticks = 0u;
    uint64_t now_us = 0u;      /* the plant's time, extended past the 32-bit wrap */
    uint32_t last_time_us = 0u;
    bool have_time = false;

    printf("rw_sil ready cmd_port=%u plant_port=%u serial=%s\n", link.port, lockstep.port, serial.path);
    fflush(stdout);

    int exit_code = 0;
    int silent_ms = 0;
    while (!stop_requested) {
        int got = sil_lockstep_wait_sensors(&lockstep, 100);
        if (got <= 0) {
            silent_ms += 100;
            if (silent_ms >= plant_timeout_s * 1000) {
                fprintf(stderr, "rw_sil: no SIL_SENSORS from the plant for %ld s, exiting\n", plant_timeout_s);
                exit_code = 3;
                break;
            }
            continue;
        }
        silent_ms = 0;
        const uint32_t time_us = lockstep.sensors.time_us;
        now_us = have_time ? now_us + (uint32_t)(time_us - last_time_us) : time_us;
        last_time_us = time_us;
        have_time = true;
        /* the NINA module at this time (access point, association): whether datagrams pass this tick */
        sil_wifi_link_update(&wifi, now_us);
        if (!booted) {
            /* the board's setup(): the WiFi boot runs before the tick starts; the ESCs hold the bottom pulse */
            booted = sil_wifi_link_boot_step(&wifi, now_us);
            sil_wifi_link_update(&wifi, now_us);
            if (booted) {
                sil_board_report_begin(&report, (uint32_t)(now_us / 1000u));
            }
        }
        if (!sil_link_wait_for(&link, lockstep.sensors.host_frames_sent, 2000)) {
            fprintf(stderr, "rw_sil: lockstep barrier: %u host frames announced, %u received\n",
                    (unsigned)lockstep.sensors.host_frames_sent, (unsigned)link.received_total);
        }
        if (!booted) { /* the HAL's PWM, begun at the bottom pulse, until the tick writes its own */
            lockstep.esc_staged_third_us = (uint16_t)(3u * RW_ESC_PULSE_LIMIT_LOW_US);
            sil_lockstep_apply_esc(&lockstep);
            sil_lockstep_send_actuators(&lockstep);
            continue;
        }
        sil_scheduler_on_tick(&scheduler, lockstep.sensors.time_us);
        sil_lockstep_apply_esc(&lockstep);
        rw_core_tick(&core, &hal, lockstep.sensors.time_us);
        ++ticks;
        if (first_tick) { /* the record is loaded: the credentials in use (as the board's link begin) */
            first_tick = false;
            sil_wifi_link_take_credentials(&wifi, &core.state.config);
            link_commits = core.state.config.commits;
        }
        /* the background loop between this tick and the next: the spindle's bus transactions */
        sil_spindle_bus_service(&spindle_bus, &lockstep.sensors);
        /* and the flash: a PROVISION_COMMIT's write, save_ticks after its request */
        sil_config_store_service(&store);
        /* the WiFi link: one step of its policy; a PROVISION_COMMIT's credentials while the rope is down */
        const bool down = rope_down(core.state.state);
        sil_wifi_link_service(&wifi, now_us, down);
        if (down && core.state.config.commits != link_commits) {
            link_commits = core.state.config.commits;
            sil_wifi_link_reconfigure(&wifi, now_us, &core.state.config);
        }
        sil_board_report_service(&report, (uint32_t)(now_us / 1000u), &serial, &wifi, ticks, scheduler.overruns);
        lockstep.spindle_moving_speed_raw = spindle_bus.moving_speed_raw;
        sil_lockstep_send_actuators(&lockstep);
    }
    const rw_spindle_exchange_counters *sc = &spindle_bus.exchange.counters;
    fprintf(stderr,
            "rw_sil spindle_bus requests=%u taken=%u missing=%u late=%u reads_ok=%u reads_failed=%u writes_ok=%u "
            "writes_failed=%u\n",
            (unsigned)sc->requests, (unsigned)sc->taken, (unsigned)sc->missing, (unsigned)sc->late,
            (unsigned)sc->reads_ok, (unsigned)sc->reads_failed, (unsigned)sc->writes_ok, (unsigned)sc->writes_failed);
    fprintf(stderr, "rw_sil flash requests=%u refused_busy=%u writes_ok=%u writes_failed=%u\n",
            (unsigned)store.requests, (unsigned)store.refused_busy, (unsigned)store.writes_ok,
            (unsigned)store.writes_failed);
    const rw_wifi_supervisor_counters *wc = &wifi.supervisor.counters;
    const sil_nina_counters *nc = &wifi.nina.counters;
    fprintf(stderr,
            "rw_sil wifi state=%s booted=%d boot_ms=%u polls=%u connects=%u losses=%u attempts=%u deferred=%u "
            "module_busy=%u module_hangs=%u ready_waits_expired=%u calls=%u calls_while_busy=%u associations=%u "
            "association_losses=%u sockets_opened=%u passes=%u passes_skipped=%u max_pass_us=%u rx=%u tx=%u "
            "lost_rx=%u lost_tx=%u\n",
            wifi_state_name(sil_wifi_link_state(&wifi)), booted ? 1 : 0, (unsigned)wifi.counters.boot_ms,
            (unsigned)wc->polls, (unsigned)wc->connects, (unsigned)wc->losses, (unsigned)wc->attempts,
            (unsigned)wc->deferred, (unsigned)wc->module_busy, (unsigned)wc->module_hangs,
            (unsigned)wifi.counters.ready_waits_expired, (unsigned)nc->calls, (unsigned)nc->calls_while_busy,
            (unsigned)nc->associations, (unsigned)nc->association_losses, (unsigned)nc->sockets_opened,
            (unsigned)wifi.counters.passes, (unsigned)wifi.counters.passes_skipped,
            (unsigned)wifi.counters.max_pass_us, (unsigned)link.delivered, (unsigned)link.sent,
            (unsigned)link.lost_rx, (unsigned)link.lost_tx);
    fprintf(stderr, "rw_sil led on=%d on_ticks=%u off_ticks=%u changes=%u last_change_ms=%u ticks=%u overruns=%u "
                    "usb_notes=%u usb_notes_dropped=%u\n",
            report.led_on ? 1 : 0, (unsigned)report.led_on_ticks, (unsigned)report.led_off_ticks,
            (unsigned)report.led_changes, (unsigned)report.led_last_change_ms, (unsigned)ticks,
            (unsigned)scheduler.overruns, (unsigned)serial.notes, (unsigned)serial.notes_dropped);
    sil_link_close(&link);
    sil_lockstep_close(&lockstep);
    sil_serial_close(&serial);
    return exit_code;
}
