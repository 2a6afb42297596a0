/* USB CDC link with COBS framing (see arduino_serial_link.h for the non-blocking rules).
 *
 * Why the USB registers: Serial_::write (ArduinoCore-samd USBDeviceClass::send) copies up to 64 bytes into
 * the endpoint's bank and, if the host has not yet taken the previous packet (EPSTATUS.BK1RDY still set),
 * first waits for it up to TX_TIMEOUT_MS = 70 ms. Writing at most 63 bytes and only while BK1RDY is clear
 * makes that wait impossible: the write returns after one memcpy. The endpoint number is found from the
 * endpoint configuration (the only bulk IN endpoint of a sketch without other USB classes). */
#include "arduino_serial_link.h"

#include <Arduino.h>
#include <string.h>

namespace {

const uint8_t USB_EPTYPE_BULK = 3u; /* EPCFG.EPTYPE1 value of a bulk IN bank */

/* The CDC bulk IN endpoint, or 0 while USB is not configured. */
uint8_t find_in_endpoint(void)
{
    for (uint8_t ep = 1u; ep < USB_EPT_NUM; ++ep) {
        if (USB->DEVICE.DeviceEndpoint[ep].EPCFG.bit.EPTYPE1 == USB_EPTYPE_BULK) {
            return ep;
        }
    }
    return 0u;
}

bool host_listening(void)
{
    return USBDevice.configured() && Serial.dtr();
}

/* Hand one packet of the queue to USB if the IN bank is free. */
void pump(rw_arduino_serial_link *link)
{
    if (link->tx_len == 0u) {
        return;
    }
    if (!host_listening()) {
        link->tx_len = 0u;
        return;
    }
    if (link->in_endpoint == 0u) {
        link->in_endpoint = find_in_endpoint();
        if (link->in_endpoint == 0u) {
            return;
        }
    }
    if (USB->DEVICE.DeviceEndpoint[link->in_endpoint].EPSTATUS.bit.BK1RDY) {
        return; /* the host has not taken the previous packet yet */
    }
    const size_t n = link->tx_len < RW_SERIAL_PACKET_BYTES ? link->tx_len : RW_SERIAL_PACKET_BYTES;
    (void)Serial.write(link->tx, n);
    link->tx_len -= n;
    memmove(link->tx, link->tx + n, link->tx_len);
}

size_t serial_recv(void *ctx, uint8_t *buf, size_t cap)
{
    rw_arduino_serial_link *link = static_cast<rw_arduino_serial_link *>(ctx);
    /* Serial.read() takes one byte from the CDC receive buffer and never waits (-1: empty) */
    for (int byte = Serial.read(); byte >= 0; byte = Serial.read()) {
        const size_t len = rw_cobs_deframer_put(&link->rx, static_cast<uint8_t>(byte), buf, cap);
        if (len != 0u) {
            return len;
        }
    }
    return 0u;
}

void serial_send(void *ctx, const uint8_t *frame, size_t len)
{
    rw_arduino_serial_link *link = static_cast<rw_arduino_serial_link *>(ctx);
    if (!host_listening()) {
        link->tx_len = 0u;
        ++link->tx_dropped;
        return;
    }
    const size_t space = RW_SERIAL_TX_BYTES - link->tx_len;
    const size_t n = space > 1u ? rw_cobs_encode(frame, len, link->tx + link->tx_len, space - 1u) : 0u;
    if (n == 0u) {
        ++link->tx_dropped;
        return;
    }
    link->tx[link->tx_len + n] = 0u;
    link->tx_len += n + 1u;
    ++link->frames_out;
    pump(link);
}

void serial_accept_peer(void *ctx)
{
    (void)ctx; /* one cable, one peer */
}

} // namespace

void rw_arduino_serial_link_begin(rw_arduino_serial_link *link)
{
    memset(link, 0, sizeof *link);
    Serial.begin(115200);
    Serial.setTimeout(0); /* readBytes returns what is there, never waits */
}

void rw_arduino_serial_link_service(rw_arduino_serial_link *link)
{
    pump(link);
}

rw_hal_link rw_arduino_serial_link_hal(rw_arduino_serial_link *link)
{
    rw_hal_link hal;
    hal.ctx = link;
    hal.recv = serial_recv;
    hal.reply = serial_send;
    hal.accept_peer = serial_accept_peer;
    hal.send = serial_send;
    return hal;
}
