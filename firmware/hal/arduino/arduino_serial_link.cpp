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

/* Move what USB has received into rx (at most its free space). */
void fill(rw_arduino_serial_link *link)
{
    const int available = Serial.available();
    if (available <= 0) {
        return;
    }
    if (link->rx_len == RW_SERIAL_RX_BYTES) { /* no delimiter in a full buffer: drop the frame's bytes */
        link->rx_overflow = true;
        link->rx_len = 0u;
    }
    size_t want = static_cast<size_t>(available);
    const size_t space = RW_SERIAL_RX_BYTES - link->rx_len;
    if (want > space) {
        want = space;
    }
    /* in chunks: the core's USB receive copies out of its ring buffer with interrupts masked, so a chunk
     * bounds the masked time (RW_SERIAL_READ_CHUNK_BYTES, about 5 us) and with it the tick's entry latency */
    while (want > 0u) {
        const size_t chunk = want < RW_SERIAL_READ_CHUNK_BYTES ? want : RW_SERIAL_READ_CHUNK_BYTES;
        const size_t got = Serial.readBytes(reinterpret_cast<char *>(link->rx + link->rx_len), chunk);
        link->rx_len += got;
        want -= got;
        if (got < chunk) {
            return;
        }
    }
}

/* Decode the first complete frame in rx into the queue (if it has room). */
void decode_one(rw_arduino_serial_link *link)
{
    for (;;) {
        const uint8_t *end = static_cast<const uint8_t *>(memchr(link->rx, 0, link->rx_len));
        if (end == nullptr) {
            return;
        }
        const size_t n = static_cast<size_t>(end - link->rx);
        const bool overflow = link->rx_overflow;
        if (n == 0u && !overflow) { /* back-to-back delimiters */
            link->rx_len -= 1u;
            memmove(link->rx, link->rx + 1u, link->rx_len);
            continue;
        }
        rw_frame_queue_slot *slot = rw_frame_queue_reserve(&link->rx_frames);
        if (slot == nullptr) {
            return; /* the tick has not taken the earlier ones: keep the bytes */
        }
        size_t len = 0u;
        if (n != 0u && !overflow) {
            len = rw_cobs_decode(link->rx, n, slot->bytes, sizeof slot->bytes);
        }
        link->rx_overflow = false;
        link->rx_len -= n + 1u;
        memmove(link->rx, link->rx + n + 1u, link->rx_len);
        slot->addr = 0u;
        slot->port = 0u;
        if (len == 0u) {
            ++link->bad_frames;
            slot->bytes[0] = 0u; /* not a frame: the core refuses it (BAD_MAGIC) and counts it */
            len = 1u;
        } else {
            ++link->frames_in;
        }
        slot->len = static_cast<uint16_t>(len);
        rw_frame_queue_publish(&link->rx_frames);
        return;
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
    rw_frame_queue_init(&link->rx_frames);
    rw_frame_queue_init(&link->tx_frames);
    Serial.begin(115200);
    Serial.setTimeout(0); /* readBytes returns what is there, never waits */
}

void rw_arduino_serial_link_service(rw_arduino_serial_link *link)
{
    fill(link);
    decode_one(link);
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
