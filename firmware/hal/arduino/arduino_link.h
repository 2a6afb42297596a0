/* Datagram link on the board: WiFiNINA in station mode, one UDP socket. Implements rw_hal_link
 * (hal/rw_hal_link.h): at most one datagram read per tick, each datagram written in one
 * beginPacket/write/endPacket, replies to the sender of the last datagram, telemetry to the accepted peer. */
#ifndef RW_ARDUINO_LINK_H
#define RW_ARDUINO_LINK_H

#include <stddef.h>
#include <stdint.h>

extern "C" {
#include "rw_config.h"
#include "rw_hal_link.h"
}

/* UDP port the board listens on (a board setting, not in the configuration record). */
static const uint16_t RW_LINK_UDP_PORT = 14550u;

/* Connection attempt at boot: WiFi.begin blocks at most this long (the watchdog is fed meanwhile). */
static const uint32_t RW_LINK_BOOT_CONNECT_TIMEOUT_MS = 15000u;
/* While running, WiFi.status() is polled this often (one SPI exchange with the NINA module). */
static const uint32_t RW_LINK_STATUS_POLL_MS = 500u;
/* After a loss, a new connection is started this often while the ESCs are at idle. */
static const uint32_t RW_LINK_RECONNECT_INTERVAL_MS = 5000u;

enum rw_link_state {
    RW_LINK_NOT_PROVISIONED = 0, /* no SSID stored: stays down */
    RW_LINK_NO_MODULE = 1,       /* the NINA module does not answer */
    RW_LINK_CONNECTING = 2,
    RW_LINK_UP = 3,              /* associated, DHCP address, UDP socket open */
};

struct rw_arduino_link {
    /* Credentials in use: copied from the core's configuration record (rw_config) at begin and after each
     * PROVISION_COMMIT (rw_arduino_link_reconfigure), never from staged, uncommitted provisioning. */
    char ssid[RW_CONFIG_SSID_LEN];
    char password[RW_CONFIG_PASSWORD_LEN];
    uint16_t port;
    uint8_t state;              /* rw_link_state */
    bool have_sender;           /* a datagram was received since the link came up */
    bool have_peer;
    uint32_t sender_ip;         /* sender of the last received datagram (IPv4, as IPAddress's uint32_t) */
    uint16_t sender_port;
    uint32_t peer_ip;           /* the accepted peer: telemetry and events go here */
    uint16_t peer_port;
    uint32_t last_poll_ms;
    uint32_t last_attempt_ms;
    uint32_t connects;          /* successful connections since boot */
    uint32_t losses;            /* connection losses since boot */
    uint32_t send_failures;     /* beginPacket/endPacket refusals */
    uint32_t rx_truncated;      /* datagrams longer than the core's buffer */
};

/* Bring the link up with the credentials of config (the core's record, loaded by its first tick): NINA
 * reset and checked (always, also unprovisioned, so a later connection never waits for the module's
 * reset), then if an SSID is stored: WiFi.begin blocking at most RW_LINK_BOOT_CONNECT_TIMEOUT_MS with the
 * watchdog fed, noLowPowerMode, the UDP socket on port. Returns the state reached (RW_LINK_UP on success;
 * CONNECTING means it keeps trying in service()). */
rw_link_state rw_arduino_link_begin(rw_arduino_link *link, const rw_config *config, uint16_t port);

/* After a PROVISION_COMMIT: take the record's credentials; if they changed, drop the connection and start
 * a new one at once without waiting (WiFi.setTimeout(0)), or stay down when the SSID is now empty. Only
 * called while the ESCs are at idle (provisioning is refused unless DISARMED). */
void rw_arduino_link_reconfigure(rw_arduino_link *link, const rw_config *config);

/* Once per loop: polls the connection every RW_LINK_STATUS_POLL_MS and, after a loss, starts a new
 * connection (non-blocking) every RW_LINK_RECONNECT_INTERVAL_MS - only when may_block is true, i.e. when
 * the ESCs are at idle, because every WiFiNINA call can take milliseconds. */
void rw_arduino_link_service(rw_arduino_link *link, uint32_t now_ms, bool may_block);

rw_hal_link rw_arduino_link_hal(rw_arduino_link *link);

#endif /* RW_ARDUINO_LINK_H */
