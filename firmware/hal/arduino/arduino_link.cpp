/* WiFiNINA station + UDP. Every WiFiNINA call is an SPI exchange with the NINA-W102 module (tens to
 * hundreds of microseconds), so the per-tick work is kept to what the core asks: one parsePacket (and a
 * read when something arrived) and at most one beginPacket/write/endPacket.
 *
 * Connection handling:
 *  - boot: WiFi.begin blocks up to RW_LINK_BOOT_CONNECT_TIMEOUT_MS (WiFi.setTimeout) while WiFiNINA feeds
 *    our watchdog through WiFi.setFeedWatchdogFunc; the ESC PWM already runs at the minimum pulse then.
 *  - low-power mode off (WiFi.noLowPowerMode) after every connection: with it on, the module sleeps
 *    between beacons and adds 100+ ms of latency to every datagram.
 *  - loss: WiFi.status() every RW_LINK_STATUS_POLL_MS; when not connected the socket is closed and the
 *    core sees the host fall silent (heartbeat loss -> spin-down). A new connection is started with
 *    WiFi.setTimeout(0), so WiFi.begin only hands the credentials to the module and returns; the result
 *    is picked up by later polls. It is started only while the caller says blocking is acceptable (ESCs
 *    at idle), because the credential exchange still costs a few SPI transfers. */
#include "arduino_link.h"

#include <Arduino.h>
#include <string.h>
#include <WiFiNINA.h>
#include <WiFiUdp.h>

#include "arduino_watchdog.h"

namespace {

WiFiUDP udp;

void start_connect(rw_arduino_link *link)
{
    if (link->password[0] != '\0') {
        (void)WiFi.begin(link->ssid, link->password);
    } else {
        (void)WiFi.begin(link->ssid);
    }
}

void on_connected(rw_arduino_link *link)
{
    WiFi.noLowPowerMode();
    if (udp.begin(link->port) == 1) {
        link->state = RW_LINK_UP;
        link->have_sender = false;
        ++link->connects;
    } else {
        link->state = RW_LINK_CONNECTING; /* no socket: try again at the next poll */
    }
}

void on_lost(rw_arduino_link *link)
{
    udp.stop();
    link->state = RW_LINK_CONNECTING;
    link->have_sender = false;
    link->have_peer = false;
    ++link->losses;
}

void send_to(rw_arduino_link *link, uint32_t ip, uint16_t port, const uint8_t *frame, size_t len)
{
    if (link->state != RW_LINK_UP) {
        return;
    }
    if (udp.beginPacket(IPAddress(ip), port) != 1) {
        ++link->send_failures;
        return;
    }
    (void)udp.write(frame, len);
    if (udp.endPacket() != 1) {
        ++link->send_failures;
    }
}

size_t link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    if (link->state != RW_LINK_UP) {
        return 0u;
    }
    const int available = udp.parsePacket(); /* drops what was left of the previous datagram */
    if (available <= 0) {
        return 0u;
    }
    link->sender_ip = static_cast<uint32_t>(udp.remoteIP());
    link->sender_port = udp.remotePort();
    link->have_sender = true;
    const size_t n = static_cast<size_t>(available);
    const int got = udp.read(buf, n > cap ? cap : n);
    if (got <= 0) {
        return 0u;
    }
    if (n > cap) {
        ++link->rx_truncated;
        return cap + 1u; /* the core refuses it as OVERSIZE */
    }
    return static_cast<size_t>(got);
}

void link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    if (link->have_sender) {
        send_to(link, link->sender_ip, link->sender_port, frame, len);
    }
}

void link_accept_peer(void *ctx)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    if (link->have_sender) {
        link->peer_ip = link->sender_ip;
        link->peer_port = link->sender_port;
        link->have_peer = true;
    }
}

void link_send(void *ctx, const uint8_t *frame, size_t len)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    if (link->have_peer) {
        send_to(link, link->peer_ip, link->peer_port, frame, len);
    }
}

/* Copy the record's credentials (always NUL-terminated); true if they differ from those in use. */
bool take_credentials(rw_arduino_link *link, const rw_config *config)
{
    char ssid[RW_CONFIG_SSID_LEN];
    char password[RW_CONFIG_PASSWORD_LEN];
    memcpy(ssid, config->wifi_ssid, sizeof ssid);
    memcpy(password, config->wifi_password, sizeof password);
    ssid[sizeof ssid - 1u] = '\0';
    password[sizeof password - 1u] = '\0';
    if (config->password_set == 0u) {
        password[0] = '\0';
    }
    const bool changed = strcmp(ssid, link->ssid) != 0 || strcmp(password, link->password) != 0;
    memcpy(link->ssid, ssid, sizeof ssid);
    memcpy(link->password, password, sizeof password);
    return changed;
}

} // namespace

rw_link_state rw_arduino_link_begin(rw_arduino_link *link, const rw_config *config, uint16_t port)
{
    link->ssid[0] = '\0';
    link->password[0] = '\0';
    (void)take_credentials(link, config);
    link->port = port;
    link->have_sender = false;
    link->have_peer = false;
    link->sender_ip = link->peer_ip = 0u;
    link->sender_port = link->peer_port = 0u;
    link->connects = link->losses = link->send_failures = link->rx_truncated = 0u;
    link->last_poll_ms = link->last_attempt_ms = millis();
    if (WiFi.status() == WL_NO_MODULE) { /* the first call also resets and starts the module (~0.75 s) */
        link->state = RW_LINK_NO_MODULE;
        return RW_LINK_NO_MODULE;
    }
    if (link->ssid[0] == '\0') {
        link->state = RW_LINK_NOT_PROVISIONED;
        return RW_LINK_NOT_PROVISIONED;
    }
    WiFi.setFeedWatchdogFunc(rw_arduino_watchdog_feed_callback);
    WiFi.setTimeout(RW_LINK_BOOT_CONNECT_TIMEOUT_MS);
    link->state = RW_LINK_CONNECTING;
    start_connect(link);
    WiFi.setTimeout(0u); /* from now on WiFi.begin never waits */
    if (WiFi.status() == WL_CONNECTED) {
        on_connected(link);
    }
    link->last_attempt_ms = millis();
    return static_cast<rw_link_state>(link->state);
}

void rw_arduino_link_service(rw_arduino_link *link, uint32_t now_ms, bool may_block)
{
    if (link->state == RW_LINK_NOT_PROVISIONED || link->state == RW_LINK_NO_MODULE) {
        return;
    }
    if (now_ms - link->last_poll_ms < RW_LINK_STATUS_POLL_MS) {
        return;
    }
    link->last_poll_ms = now_ms;
    const uint8_t status = WiFi.status();
    if (link->state == RW_LINK_UP) {
        if (status != WL_CONNECTED) {
            on_lost(link);
            link->last_attempt_ms = now_ms - RW_LINK_RECONNECT_INTERVAL_MS; /* may retry at once */
        }
        return;
    }
    if (status == WL_CONNECTED) {
        on_connected(link);
    } else if (may_block && now_ms - link->last_attempt_ms >= RW_LINK_RECONNECT_INTERVAL_MS) {
        start_connect(link);
        link->last_attempt_ms = now_ms;
    }
}

rw_hal_link rw_arduino_link_hal(rw_arduino_link *link)
{
    rw_hal_link hal;
    hal.ctx = link;
    hal.recv = link_recv;
    hal.reply = link_reply;
    hal.accept_peer = link_accept_peer;
    hal.send = link_send;
    return hal;
}

void rw_arduino_link_reconfigure(rw_arduino_link *link, const rw_config *config)
{
    if (!take_credentials(link, config) || link->state == RW_LINK_NO_MODULE) {
        return;
    }
    if (link->state == RW_LINK_UP) {
        on_lost(link);
        --link->losses; /* not a loss: a new network */
    }
    (void)WiFi.disconnect();
    if (link->ssid[0] == '\0') {
        link->state = RW_LINK_NOT_PROVISIONED;
        return;
    }
    link->state = RW_LINK_CONNECTING;
    WiFi.setTimeout(0u);
    start_connect(link);
    link->last_attempt_ms = link->last_poll_ms = millis();
}
