/* The board's WiFi connection policy, as a pure state machine the background loop asks what to do next.
 *
 * It never waits: each call answers with one action (or none) for this pass of the background loop, and the
 * caller does it and reports back. The rules:
 *  - Every WiFiNINA call waits for the NINA module's ready line without a time limit, so the caller only calls
 *    into the library while the line says ready (module_ready). A line that stays busy for module_hung_ms makes
 *    the link NO_MODULE for good (until reset): counted, and the status LED and USB say so.
 *  - The connection is polled every status_poll_ms (one status exchange).
 *  - Connection steps (start connecting: WiFi.begin with the credentials; open the socket after an association:
 *    noLowPowerMode + udp.begin) are taken only while the rope is down (rope_down): in flight they are deferred
 *    (counted once per deferral) until it is. A loss is acted on at once (the socket closes).
 *  - A new connection is started at most every reconnect_interval_ms (right away after a loss).
 *  - While UP, the caller may move datagrams (RW_WIFI_DO_IO).
 * Pure: time comes in as now_ms, no I/O. */
#ifndef RW_WIFI_SUPERVISOR_H
#define RW_WIFI_SUPERVISOR_H

#include <stdbool.h>
#include <stdint.h>

/* The bounds the HAL keeps around the policy's calls (board: hal/arduino/arduino_link.cpp; SIL:
 * hal/sil/sil_wifi_link.c). */
/* At boot, after its reset, the NINA module must raise its ready line within this time, else NO_MODULE. */
#define RW_WIFI_BOOT_READY_MS 2000u
/* Connection attempt at boot: WiFi.begin blocks at most this long (the watchdog is fed meanwhile). */
#define RW_WIFI_BOOT_CONNECT_TIMEOUT_MS 15000u
/* Within one datagram's or one step's calls the ready line is awaited at most this long before each call;
 * longer and the step is abandoned (counted), the pass ends. */
#define RW_WIFI_CALL_READY_WAIT_US 2000u

/* The link's state (same values as the board's rw_link_state). */
typedef enum {
    RW_WIFI_NOT_PROVISIONED = 0, /* no SSID stored: stays down */
    RW_WIFI_NO_MODULE = 1,       /* the NINA module does not answer (at boot, or its ready line hung) */
    RW_WIFI_CONNECTING = 2,
    RW_WIFI_UP = 3,              /* associated, UDP socket open */
} rw_wifi_state;

typedef enum {
    RW_WIFI_DO_NOTHING = 0,
    RW_WIFI_DO_POLL_STATUS = 1,   /* WiFi.status(), then rw_wifi_supervisor_status */
    RW_WIFI_DO_START_CONNECT = 2, /* WiFi.begin(ssid, password) without waiting */
    RW_WIFI_DO_OPEN_SOCKET = 3,   /* noLowPowerMode + udp.begin, then rw_wifi_supervisor_socket */
    RW_WIFI_DO_CLOSE_SOCKET = 4,  /* udp.stop after a loss */
    RW_WIFI_DO_IO = 5,            /* receive and send datagrams (at most one each) */
} rw_wifi_action;

typedef struct rw_wifi_supervisor_config {
    uint32_t status_poll_ms;        /* 500 */
    uint32_t reconnect_interval_ms; /* 5000 */
    uint32_t module_hung_ms;        /* 1000: the ready line busy this long = no module */
} rw_wifi_supervisor_config;

typedef struct rw_wifi_supervisor_counters {
    uint32_t polls;           /* status polls asked for */
    uint32_t connects;        /* sockets opened (link UP) */
    uint32_t losses;          /* UP -> CONNECTING */
    uint32_t attempts;        /* connections started */
    uint32_t deferred;        /* connection steps deferred because the rope was up */
    uint32_t module_busy;     /* passes the module's ready line was busy (no call made) */
    uint32_t module_hangs;    /* NO_MODULE reached because the ready line stayed busy */
} rw_wifi_supervisor_counters;

typedef struct rw_wifi_supervisor {
    rw_wifi_supervisor_config cfg;
    uint8_t state;            /* rw_wifi_state */
    bool associated;          /* the last poll said connected (socket not yet open while CONNECTING) */
    bool close_pending;       /* a loss was seen: close the socket next */
    bool deferring;           /* a step is being deferred (counted once per deferral) */
    bool busy;                /* the ready line was busy at the last step */
    uint32_t busy_since_ms;
    uint32_t last_poll_ms;
    uint32_t last_attempt_ms;
    rw_wifi_supervisor_counters counters;
} rw_wifi_supervisor;

#ifdef __cplusplus
extern "C" {
#endif

void rw_wifi_supervisor_config_defaults(rw_wifi_supervisor_config *cfg);
/* Start in state (what the boot reached), at now_ms; last_attempt_ms = now_ms (a boot attempt just ran). */
void rw_wifi_supervisor_init(rw_wifi_supervisor *s, const rw_wifi_supervisor_config *cfg, rw_wifi_state state,
                             uint32_t now_ms);
/* New credentials (PROVISION_COMMIT, rope down): provisioned -> CONNECTING with a connection started by the
 * caller now; else NOT_PROVISIONED. NO_MODULE stays. */
void rw_wifi_supervisor_restart(rw_wifi_supervisor *s, bool provisioned, uint32_t now_ms);

/* One pass: what to do now. module_ready: the module's ready line says ready (the caller reads it). */
rw_wifi_action rw_wifi_supervisor_step(rw_wifi_supervisor *s, uint32_t now_ms, bool module_ready, bool rope_down);
/* The answer of RW_WIFI_DO_POLL_STATUS: associated with the network or not. */
void rw_wifi_supervisor_status(rw_wifi_supervisor *s, uint32_t now_ms, bool connected);
/* The outcome of RW_WIFI_DO_OPEN_SOCKET. */
void rw_wifi_supervisor_socket(rw_wifi_supervisor *s, bool opened);

#ifdef __cplusplus
}
#endif

#endif /* RW_WIFI_SUPERVISOR_H */
