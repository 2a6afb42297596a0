/* The NINA-W102 WiFi module in SIL: a small model of what the board's WiFiNINA calls see, stepped once per tick
 * (sil_nina_update) as the plant's clock goes; the SIL link (sil_wifi_link.h) drives it through
 * core/rw_wifi_supervisor.h exactly as the board's arduino_link.cpp drives the real module.
 *
 * Modelled: the module's ready line (busy after its reset until it has started; busy for a while after each
 * call: the module still working on it), association with the access point (taking associate_ms after
 * WiFi.begin; lost while the access point is out of reach; re-made by the module itself once it is back, as the
 * NINA firmware does after a WiFi.begin), low-power mode and the one UDP socket. Datagrams pass between the
 * host and the core only while the module is associated and its socket is open (sil_nina_passes_datagrams).
 * Not modelled: the SPI bytes of each call, the module's receive buffer limits, DHCP.
 *
 * Faults (scriptable, rw_sil --wifi-*): a module that never raises its ready line after reset (a hung module:
 * boot reaches NO_MODULE), one that is slow to start, an access point out of reach over a chosen span of
 * plant time, and a module that keeps its ready line busy for busy_after_call_us after each call (a slow
 * module: the HAL's bounded waits expire). Relays only: no physics, no clock of its own (times come in). */
#ifndef SIL_NINA_H
#define SIL_NINA_H

#include <stdbool.h>
#include <stdint.h>

/* A fault time that never comes. */
#define SIL_NINA_NEVER UINT32_MAX
/* Bus time of one WiFiNINA call (one SPI command and its answer at 8 MHz, with the library's waits), us. */
#define SIL_NINA_CALL_US 60u

typedef struct sil_nina_faults {
    uint32_t boot_ready_ms;      /* after its reset the ready line says ready this late (SIL_NINA_NEVER: never) */
    uint32_t associate_ms;       /* association with the access point takes this long */
    uint32_t ap_lost_at_ms;      /* the access point is out of reach from this plant time (SIL_NINA_NEVER: never) */
    uint32_t ap_back_at_ms;      /* ... until this one (SIL_NINA_NEVER: for good) */
    uint32_t busy_after_call_us; /* the ready line stays busy this long after each call (0: a healthy module) */
    uint32_t slow_from_ms;       /* busy_after_call_us applies from this plant time on (0: from boot) */
} sil_nina_faults;

typedef struct sil_nina_counters {
    uint32_t calls;              /* WiFiNINA calls the HAL made */
    uint32_t calls_while_busy;   /* calls made while the ready line was busy: WiFiNINA waited for it (no limit) */
    uint32_t associations;       /* associations made (at boot, by WiFi.begin, or by the module itself) */
    uint32_t association_losses; /* associations lost (access point out of reach) */
    uint32_t sockets_opened;     /* udp.begin that succeeded */
} sil_nina_counters;

typedef struct sil_nina {
    sil_nina_faults faults;
    uint64_t ready_at_us;        /* the ready line says ready from this time on (UINT64_MAX: never) */
    uint64_t associate_at_us;    /* an association under way completes at this time */
    bool reset_done;             /* wifiDriverInit ran */
    bool joining;                /* WiFi.begin was given credentials: the module (re)associates when it can */
    bool associating;            /* an association is under way */
    bool associated;
    bool ap_in_reach;
    bool low_power;              /* the module's default: on until noLowPowerMode */
    bool socket_open;
    sil_nina_counters counters;
} sil_nina;

void sil_nina_init(sil_nina *n, const sil_nina_faults *faults);
/* The module's state at plant time now_us (one step per tick): the access point's reach, associations. */
void sil_nina_update(sil_nina *n, uint64_t now_us);

/* The ready line at t_us (what the HAL reads before any call). */
bool sil_nina_ready(const sil_nina *n, uint64_t t_us);
/* When the ready line next says ready (UINT64_MAX: never). */
uint64_t sil_nina_ready_at(const sil_nina *n);
/* Datagrams reach the socket (and leave it): associated and the socket open. */
bool sil_nina_passes_datagrams(const sil_nina *n);

/* The calls (WiFiNINA), each made at t_us; each returns the time its answer is back (t_us + SIL_NINA_CALL_US). */
/* WiFiDrv::wifiDriverInit: reset; the ready line rises boot_ready_ms later (or never). */
uint64_t sil_nina_reset(sil_nina *n, uint64_t t_us);
/* WiFi.status(): *connected = associated. */
uint64_t sil_nina_status(sil_nina *n, uint64_t t_us, bool *connected);
/* WiFi.begin(ssid[, password]) without waiting: credentials handed over, association starts. */
uint64_t sil_nina_begin(sil_nina *n, uint64_t t_us);
/* WiFi.disconnect(): association dropped, credentials forgotten. */
uint64_t sil_nina_disconnect(sil_nina *n, uint64_t t_us);
/* WiFi.noLowPowerMode(). */
uint64_t sil_nina_no_low_power(sil_nina *n, uint64_t t_us);
/* udp.begin(port): *opened = the socket is open (only while associated). */
uint64_t sil_nina_udp_begin(sil_nina *n, uint64_t t_us, bool *opened);
/* udp.stop(). */
uint64_t sil_nina_udp_stop(sil_nina *n, uint64_t t_us);

#endif /* SIL_NINA_H */
