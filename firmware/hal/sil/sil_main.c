/* rw_sil: the firmware core with the sil HAL, as its own process.
 *
 *   rw_sil [--cmd-port N] [--plant-port N] [--plant-timeout-s S] [--tick-us N] [--state-file PATH]
 *          [--spindle-bus-us N]
 *
 * Binds the command link (the host's UDP port, as the board's WiFi) and the plant port on 127.0.0.1
 * (0 = any free port), opens a pseudo-terminal as the board's USB serial (provisioning), prints
 * "rw_sil ready cmd_port=N plant_port=N serial=PATH" on stdout, then runs one core tick per SIL_SENSORS
 * datagram from the plant. --state-file is the board's flash (configuration record: key, parameters,
 * boot counter = session id); without it nothing persists and nothing can be committed.
 * --spindle-bus-us is the bus time of one spindle transaction (sil_spindle_bus.h, default 350). A
 * PROVISION_COMMIT's write to the state file is done between ticks, SIL_CONFIG_STORE_DEFAULT_SAVE_TICKS after
 * its request (sil_config_store.h). On exit it prints the spindle bus counters
 * ("rw_sil spindle_bus requests=N ...") and the flash counters ("rw_sil flash requests=N ...") on stderr. Exits 0 on SIGINT/SIGTERM, 3 when the plant has been silent
 * for --plant-timeout-s (never hangs), 2 on bad arguments or sockets. */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rw_core.h"
#include "sil_config_store.h"
#include "sil_link.h"
#include "sil_lockstep.h"
#include "sil_serial.h"
#include "sil_spindle_bus.h"

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
    fprintf(stderr, "rw_sil: %s\nusage: rw_sil [--cmd-port N] [--plant-port N] [--plant-timeout-s S] [--tick-us N] [--state-file PATH] [--spindle-bus-us N]\n", msg);
    return 2;
}

int main(int argc, char **argv)
{
    long cmd_port = 14550, plant_port = 14560, plant_timeout_s = 10, tick_us = 1000;
    long spindle_bus_us = SIL_SPINDLE_BUS_DEFAULT_TRANSACTION_US;
    static sil_config_store store = { .save_ticks = SIL_CONFIG_STORE_DEFAULT_SAVE_TICKS };
    for (int i = 1; i < argc; ++i) {
        long *target = NULL;
        long max = 65535;
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
        if (!sil_link_wait_for(&link, lockstep.sensors.host_frames_sent, 2000)) {
            fprintf(stderr, "rw_sil: lockstep barrier: %u host frames announced, %u received\n",
                    (unsigned)lockstep.sensors.host_frames_sent, (unsigned)link.received_total);
        }
        sil_scheduler_on_tick(&scheduler, lockstep.sensors.time_us);
        sil_lockstep_apply_esc(&lockstep);
        rw_core_tick(&core, &hal, lockstep.sensors.time_us);
        /* the background loop between this tick and the next: the spindle's bus transactions */
        sil_spindle_bus_service(&spindle_bus, &lockstep.sensors);
        /* and the flash: a PROVISION_COMMIT's write, save_ticks after its request */
        sil_config_store_service(&store);
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
    sil_link_close(&link);
    sil_lockstep_close(&lockstep);
    sil_serial_close(&serial);
    return exit_code;
}
