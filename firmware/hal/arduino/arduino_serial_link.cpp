/* USB CDC link with COBS framing (see arduino_serial_link.h: the tick only uses the queues).
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

/* Hand one packet of tx to USB if the IN bank is free. */
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

/* Received bytes into the deframer while the queue to the tick has room: each complete frame is decoded
 * straight into a queue slot. Serial.read() takes one byte from the CDC receive buffer and never waits (-1:
 * empty); the Arduino core copies it with interrupts masked, one byte, so the masked time stays a few cycles. */
void receive(rw_arduino_serial_link *link)
{
    for (size_t n = 0u; n < RW_SERIAL_RX_BYTES_PER_PASS; ++n) {
        rw_frame_queue_slot *slot = rw_frame_queue_reserve(&link->rx_frames);
        if (slot == nullptr) {
            return; /* the tick has not taken the earlier ones: leave the bytes in USB */
        }
        const int byte = Serial.read();
        if (byte < 0) {
            return;
        }
        const size_t len = rw_cobs_deframer_put(&link->deframer, static_cast<uint8_t>(byte), slot->bytes,
                                                sizeof slot->bytes);
        if (len != 0u) {
            slot->addr = 0u;
            slot->port = 0u;
            slot->len = static_cast<uint16_t>(len);
            rw_frame_queue_publish(&link->rx_frames);
        }
    }
}

/* Encode the oldest queued frame into tx. */
void encode_one(rw_arduino_serial_link *link)
{
    const rw_frame_queue_slot *slot = rw_frame_queue_peek(&link->tx_frames);
    if (slot == nullptr) {
        return;
    }
    const size_t space = RW_SERIAL_TX_BYTES - link->tx_len;
    const size_t n = host_listening() && space > 1u ? rw_cobs_encode(slot->bytes, slot->len, link->tx + link->tx_len, space - 1u) : 0u;
    if (n == 0u) {
        ++link->tx_dropped;
    } else {
        link->tx[link->tx_len + n] = 0u;
        link->tx_len += n + 1u;
        ++link->frames_out;
    }
    rw_frame_queue_release(&link->tx_frames);
}

size_t serial_recv(void *ctx, uint8_t *buf, size_t cap)
{
    rw_arduino_serial_link *link = static_cast<rw_arduino_serial_link *>(ctx);
    const rw_frame_queue_slot *slot = rw_frame_queue_peek(&link->rx_frames);
    if (slot == nullptr) {
        return 0u;
    }
    size_t len = slot->len;
    if (len > cap) {
        memcpy(buf, slot->bytes, cap);
        len = cap + 1u;
    } else {
        memcpy(buf, slot->bytes, len);
    }
    rw_frame_queue_release(&link->rx_frames);
    return len;
}

void serial_send(void *ctx, const uint8_t *frame, size_t len)
{
    rw_arduino_serial_link *link = static_cast<rw_arduino_serial_link *>(ctx);
    (void)rw_frame_queue_push(&link->tx_frames, frame, len, 0u, 0u); /* a full queue counts the drop */
}

void serial_accept_peer(void *ctx)
{
    (void)ctx; /* one cable, one peer */
}

} // namespace

void rw_arduino_serial_link_begin(rw_arduino_serial_link *link)
{
    memset(link, 0, sizeof *link);
    rw_cobs_deframer_reset(&link->deframer);
    rw_frame_queue_init(&link->rx_frames);
    rw_frame_queue_init(&link->tx_frames);
    Serial.begin(115200);
    Serial.setTimeout(0); /* readBytes returns what is there, never waits */
}

void rw_arduino_serial_link_service(rw_arduino_serial_link *link)
{
    receive(link);
    encode_one(link);
    pump(link);
}

void rw_arduino_serial_link_note(rw_arduino_serial_link *link, const char *text)
{
    const size_t n = strlen(text);
    if (!host_listening() || link->tx_len + n + 6u > RW_SERIAL_TX_BYTES) {
        ++link->tx_dropped;
        return;
    }
    memcpy(link->tx + link->tx_len, "rw: ", 4u);
    memcpy(link->tx + link->tx_len + 4u, text, n);
    link->tx[link->tx_len + 4u + n] = '\n';
    link->tx[link->tx_len + 5u + n] = 0u; /* delimiter: a host's COBS reader drops the line as one bad frame */
    link->tx_len += n + 6u;
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
