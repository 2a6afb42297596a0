/* Datagram link on the board: WiFiNINA in station mode, one UDP socket. Implements rw_hal_link
 * (hal/rw_hal_link.h) for the tick over two frame queues (core/rw_frame_queue.h): the tick only takes
 * received datagrams from one and puts datagrams to send in the other; every WiFiNINA call happens in the
 * background loop (rw_arduino_link_service), one received and one sent datagram per pass at most, only while
 * the NINA module's ready line says ready, and connection steps only while the rope is down
 * (core/rw_wifi_supervisor.h). */
#ifndef RW_ARDUINO_LINK_H
#define RW_ARDUINO_LINK_H

#include <stddef.h>
#include <stdint.h>

extern "C" {
#include "rw_config.h"
#include "rw_frame_queue.h"
#include "rw_hal_link.h"
#include "rw_wifi_supervisor.h"
}

/* UDP port the board listens on (a board setting, not in the configuration record). */
static const uint16_t RW_LINK_UDP_PORT = 14550u;

/* Connection attempt at boot: WiFi.begin blocks at most this long (the watchdog is fed meanwhile). */
static const uint32_t RW_LINK_BOOT_CONNECT_TIMEOUT_MS = RW_WIFI_BOOT_CONNECT_TIMEOUT_MS;
/* At boot, after its reset, the NINA module must raise its ready line within this time, else NO_MODULE. */
static const uint32_t RW_LINK_MODULE_BOOT_READY_MS = RW_WIFI_BOOT_READY_MS;
/* Within one datagram's calls (parsePacket, remoteIP, ...), the ready line is awaited at most this long
 * before each call; longer and the datagram is abandoned (counted), the pass ends. */
static const uint32_t RW_LINK_CALL_READY_WAIT_US = RW_WIFI_CALL_READY_WAIT_US;

enum rw_link_state {
    RW_LINK_NOT_PROVISIONED = RW_WIFI_NOT_PROVISIONED, /* no SSID stored: stays down */
    RW_LINK_NO_MODULE = RW_WIFI_NO_MODULE,             /* the NINA module does not answer */
    RW_LINK_CONNECTING = RW_WIFI_CONNECTING,
    RW_LINK_UP = RW_WIFI_UP,                           /* associated, DHCP address, UDP socket open */
};

struct rw_arduino_link {
    /* Credentials in use: copied from the core's configuration record (rw_config) at begin and after each
     * PROVISION_COMMIT (rw_arduino_link_reconfigure), never from staged, uncommitted provisioning. */
    char ssid[RW_CONFIG_SSID_LEN];
    char password[RW_CONFIG_PASSWORD_LEN];
    uint16_t port;
    rw_wifi_supervisor supervisor; /* background: the connection policy and its counters */
    rw_frame_queue rx;             /* background -> tick: received datagrams with their sender */
    rw_frame_queue tx;             /* tick -> background: datagrams with their destination */
    /* tick side */
    bool have_sender;              /* a datagram was taken since boot */
    bool have_peer;
    uint32_t sender_ip;            /* sender of the last datagram the core took (IPv4, as IPAddress's uint32_t) */
    uint16_t sender_port;
    uint32_t peer_ip;              /* the accepted peer: telemetry and events go here */
    uint16_t peer_port;
    uint32_t tx_no_peer;           /* sends with no peer yet (dropped) */
    /* background side */
    uint32_t calls;                /* WiFiNINA calls made (each one or more SPI exchanges with the module) */
    uint32_t rx_datagrams;         /* datagrams received and queued for the tick */
    uint32_t rx_abandoned;         /* datagrams abandoned: the module not ready between their calls */
    uint32_t tx_datagrams;         /* datagrams handed to the module */
    uint32_t tx_link_down;         /* datagrams dropped because the link was not up */
    uint32_t send_failures;        /* beginPacket/endPacket refusals */
    uint32_t max_service_us;       /* longest service() pass, micros() */
};

/* Bring the link up with the credentials of config (the core's record, loaded by its first tick): NINA reset
 * (always, also unprovisioned, so a later connection never waits for it) and its ready line awaited at most
 * RW_LINK_MODULE_BOOT_READY_MS (else NO_MODULE, without any call into WiFiNINA that could wait for ever); then,
 * if an SSID is stored, WiFi.begin blocking at most RW_LINK_BOOT_CONNECT_TIMEOUT_MS with the watchdog fed,
 * noLowPowerMode and the UDP socket on port. Before the tick starts. Returns the state reached. */
rw_link_state rw_arduino_link_begin(rw_arduino_link *link, const rw_config *config, uint16_t port);

/* After a PROVISION_COMMIT (background loop, rope down): take the record's credentials; if they changed, drop
 * the connection and start a new one at once without waiting, or stay down when the SSID is now empty. */
void rw_arduino_link_reconfigure(rw_arduino_link *link, const rw_config *config);

/* Background loop, every pass: one step of the connection policy (a status poll, a connection step while
 * rope_down, or datagram I/O: at most one received, one sent). Never call from the tick. */
void rw_arduino_link_service(rw_arduino_link *link, uint32_t now_ms, bool rope_down);

static inline rw_link_state rw_arduino_link_state(const rw_arduino_link *link)
{
    return static_cast<rw_link_state>(link->supervisor.state);
}

/* The tick's side: rw_hal_link over the queues. */
rw_hal_link rw_arduino_link_hal(rw_arduino_link *link);

#endif /* RW_ARDUINO_LINK_H */
