/* WiFiNINA station + UDP, driven from the background loop (arduino_link.h).
 *
 * Every WiFiNINA call is one or more SPI exchanges with the NINA-W102 module, and each starts by waiting for
 * the module's ready line (NINA_ACK low) without a time limit (SpiDrv::waitForSlaveReady). So no call is made
 * unless the line already says ready (module_ready); between the calls that make up one datagram the line is
 * awaited at most RW_LINK_CALL_READY_WAIT_US. Calls per datagram (WiFiNINA 1.9.1): received - parsePacket
 * (availData), remoteIP and remotePort (getRemoteData each), read (getDataBuf): 4; sent - beginPacket
 * (startClient), write (insertDataBuf), endPacket (sendUdpData): 3.
 *
 * Connection handling (core/rw_wifi_supervisor.h):
 *  - boot: NINA reset, ready line awaited (bounded: else NO_MODULE), then WiFi.begin blocking up to
 *    RW_LINK_BOOT_CONNECT_TIMEOUT_MS while WiFiNINA feeds our watchdog; the ESC PWM already runs at the minimum.
 *  - low-power mode off (WiFi.noLowPowerMode) with every socket opened: with it on, the module sleeps between
 *    beacons and adds 100+ ms of latency to every datagram.
 *  - WiFi.status() polled every 500 ms; on a loss the socket closes and the core sees the host fall silent
 *    (heartbeat loss -> spin-down). New connections (WiFi.begin with WiFi.setTimeout(0): only hands the
 *    credentials over) and opening the socket after an association are deferred while the rope is up. */
#include "arduino_link.h"

#include <Arduino.h>
#include <string.h>
#include <WiFiNINA.h>
#include <WiFiUdp.h>
#include <utility/wifi_drv.h>

#include "arduino_watchdog.h"

namespace {

WiFiUDP udp;

bool module_ready()
{
    return digitalRead(SPIWIFI_ACK) == LOW;
}

/* The ready line within RW_LINK_CALL_READY_WAIT_US (between the calls of one datagram). */
bool module_ready_soon()
{
    const uint32_t start_us = micros();
    while (!module_ready()) {
        if (micros() - start_us >= RW_LINK_CALL_READY_WAIT_US) {
            return false;
        }
    }
    return true;
}

void start_connect(rw_arduino_link *link)
{
    ++link->calls;
    if (link->password[0] != '\0') {
        (void)WiFi.begin(link->ssid, link->password);
    } else {
        (void)WiFi.begin(link->ssid);
    }
}

bool open_socket(rw_arduino_link *link)
{
    if (!module_ready_soon()) {
        return false;
    }
    ++link->calls;
    WiFi.noLowPowerMode();
    if (!module_ready_soon()) {
        return false;
    }
    ++link->calls;
    return udp.begin(link->port) == 1;
}

/* One received datagram into the rx queue (if one waits and the queue has room). */
void receive_one(rw_arduino_link *link)
{
    rw_frame_queue_slot *slot = rw_frame_queue_reserve(&link->rx);
    if (slot == nullptr) {
        return; /* the tick has not taken the earlier ones: leave this one in the module (counted as dropped) */
    }
    ++link->calls;
    const int available = udp.parsePacket(); /* drops what was left of the previous datagram */
    if (available <= 0) {
        return;
    }
    if (!module_ready_soon()) {
        ++link->rx_abandoned;
        return;
    }
    ++link->calls;
    slot->addr = static_cast<uint32_t>(udp.remoteIP());
    if (!module_ready_soon()) {
        ++link->rx_abandoned;
        return;
    }
    ++link->calls;
    slot->port = udp.remotePort();
    if (!module_ready_soon()) {
        ++link->rx_abandoned;
        return;
    }
    const size_t n = static_cast<size_t>(available);
    ++link->calls;
    const int got = udp.read(slot->bytes, n > sizeof slot->bytes ? sizeof slot->bytes : n);
    if (got <= 0) {
        ++link->rx_abandoned;
        return;
    }
    slot->len = n > sizeof slot->bytes ? static_cast<uint16_t>(RW_FRAME_QUEUE_OVERSIZE) : static_cast<uint16_t>(got);
    rw_frame_queue_publish(&link->rx);
    ++link->rx_datagrams;
}

/* One queued datagram to the module (beginPacket / write / endPacket). */
void send_one(rw_arduino_link *link)
{
    const rw_frame_queue_slot *slot = rw_frame_queue_peek(&link->tx);
    if (slot == nullptr || !module_ready_soon()) {
        return;
    }
    ++link->calls;
    if (udp.beginPacket(IPAddress(slot->addr), slot->port) != 1) {
        ++link->send_failures;
        rw_frame_queue_release(&link->tx);
        return;
    }
    bool ok = module_ready_soon();
    if (ok) {
        ++link->calls;
        (void)udp.write(slot->bytes, slot->len);
        ok = module_ready_soon();
    }
    if (ok) {
        ++link->calls;
        ok = udp.endPacket() == 1;
    }
    if (ok) {
        ++link->tx_datagrams;
    } else {
        ++link->send_failures;
    }
    rw_frame_queue_release(&link->tx);
}

/* While the link is not up, what the tick queued goes nowhere (counted). */
void drop_tx(rw_arduino_link *link)
{
    while (rw_frame_queue_peek(&link->tx) != nullptr) {
        rw_frame_queue_release(&link->tx);
        ++link->tx_link_down;
    }
}

size_t link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    const rw_frame_queue_slot *slot = rw_frame_queue_peek(&link->rx);
    if (slot == nullptr) {
        return 0u;
    }
    link->sender_ip = slot->addr;
    link->sender_port = slot->port;
    link->have_sender = true;
    size_t len = slot->len;
    if (len > RW_MAX_FRAME_LEN || len > cap) {
        memcpy(buf, slot->bytes, cap < RW_MAX_FRAME_LEN ? cap : RW_MAX_FRAME_LEN);
        len = cap + 1u; /* the core refuses it as OVERSIZE */
    } else {
        memcpy(buf, slot->bytes, len);
    }
    rw_frame_queue_release(&link->rx);
    return len;
}

void link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    rw_arduino_link *link = static_cast<rw_arduino_link *>(ctx);
    if (link->have_sender) {
        (void)rw_frame_queue_push(&link->tx, frame, len, link->sender_ip, link->sender_port);
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
    if (!link->have_peer) {
        ++link->tx_no_peer;
        return;
    }
    (void)rw_frame_queue_push(&link->tx, frame, len, link->peer_ip, link->peer_port);
}

/* Copy the record's credentials (always NUL-terminated); true if they differ from those in use. */
static bool take_credentials(rw_arduino_link *link, const rw_config *config)
{
    return rw_config_take_credentials(config, link->ssid, link->password);
}

rw_wifi_state boot_connect(rw_arduino_link *link)
{
    WiFiDrv::wifiDriverInit(); /* NINA reset: 10 ms low, then 750 ms for it to start */
    const uint32_t start_ms = millis();
    while (!module_ready()) {
        rw_arduino_watchdog_feed_callback();
        if (millis() - start_ms >= RW_LINK_MODULE_BOOT_READY_MS) {
            return RW_WIFI_NO_MODULE; /* no WiFiNINA call: each would wait for the line for ever */
        }
    }
    ++link->calls;
    if (WiFi.status() == WL_NO_MODULE) {
        return RW_WIFI_NO_MODULE;
    }
    if (link->ssid[0] == '\0') {
        return RW_WIFI_NOT_PROVISIONED;
    }
    WiFi.setFeedWatchdogFunc(rw_arduino_watchdog_feed_callback);
    WiFi.setTimeout(RW_LINK_BOOT_CONNECT_TIMEOUT_MS);
    start_connect(link);
    WiFi.setTimeout(0u); /* from now on WiFi.begin never waits */
    ++link->calls;
    if (!module_ready_soon() || WiFi.status() != WL_CONNECTED) {
        return RW_WIFI_CONNECTING;
    }
    return open_socket(link) ? RW_WIFI_UP : RW_WIFI_CONNECTING;
}

} // namespace

rw_link_state rw_arduino_link_begin(rw_arduino_link *link, const rw_config *config, uint16_t port)
{
    memset(link, 0, sizeof *link);
    (void)take_credentials(link, config);
    link->port = port;
    rw_frame_queue_init(&link->rx);
    rw_frame_queue_init(&link->tx);
    const rw_wifi_state reached = boot_connect(link);
    rw_wifi_supervisor_config cfg;
    rw_wifi_supervisor_config_defaults(&cfg);
    rw_wifi_supervisor_init(&link->supervisor, &cfg, reached, millis());
    if (reached == RW_WIFI_UP) {
        ++link->supervisor.counters.connects;
    }
    return static_cast<rw_link_state>(reached);
}

void rw_arduino_link_service(rw_arduino_link *link, uint32_t now_ms, bool rope_down)
{
    const uint32_t start_us = micros();
    rw_wifi_supervisor *sup = &link->supervisor;
    switch (rw_wifi_supervisor_step(sup, now_ms, module_ready(), rope_down)) {
    case RW_WIFI_DO_POLL_STATUS:
        ++link->calls;
        rw_wifi_supervisor_status(sup, now_ms, WiFi.status() == WL_CONNECTED);
        break;
    case RW_WIFI_DO_START_CONNECT:
        start_connect(link);
        break;
    case RW_WIFI_DO_OPEN_SOCKET:
        rw_wifi_supervisor_socket(sup, open_socket(link));
        break;
    case RW_WIFI_DO_CLOSE_SOCKET:
        ++link->calls;
        udp.stop();
        break;
    case RW_WIFI_DO_IO:
        receive_one(link);
        send_one(link);
        break;
    case RW_WIFI_DO_NOTHING:
    default:
        break;
    }
    if (sup->state != RW_WIFI_UP) {
        drop_tx(link);
    }
    const uint32_t took_us = micros() - start_us;
    if (took_us > link->max_service_us) {
        link->max_service_us = took_us;
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
    if (!take_credentials(link, config) || link->supervisor.state == RW_WIFI_NO_MODULE) {
        return;
    }
    const bool ready = module_ready_soon(); /* if not, the service's ready checks find out what it does */
    if (ready && link->supervisor.state == RW_WIFI_UP) {
        ++link->calls;
        udp.stop();
    }
    if (ready && module_ready_soon()) {
        ++link->calls;
        (void)WiFi.disconnect();
    }
    const bool provisioned = link->ssid[0] != '\0';
    rw_wifi_supervisor_restart(&link->supervisor, provisioned, millis());
    if (provisioned && ready && module_ready_soon()) {
        WiFi.setTimeout(0u);
        start_connect(link);
    }
}
