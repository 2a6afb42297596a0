/* USB serial link on the board: Arduino `Serial` (native USB CDC of the SAMD21), frames COBS-encoded with
 * a 0x00 delimiter (core/rw_cobs.h). Implements rw_hal_link (hal/rw_hal_link.h) for hal.serial, the
 * trusted link: provisioning (PROVISION_*) and unsigned commands from a host on the cable
 * (`wrangler provision --port /dev/ttyACM0 ...`).
 *
 * Never blocks the tick:
 *  - receive: each recv reads the bytes Serial has buffered, one at a time, into the core's COBS deframer
 *    (core/rw_cobs_deframer.h, the SIL's serial HAL uses the same) and stops at the first complete frame,
 *    leaving the rest in Serial's buffer for the next ticks;
 *  - send: the encoded frame and its delimiter are queued whole in tx, or dropped (counted) if they do
 *    not fit; the queue leaves in USB packets of at most 63 bytes, one whenever the CDC IN endpoint's bank
 *    is free (checked on the USB registers before each Serial.write). On this core Serial.availableForWrite()
 *    always answers 63 and Serial.write() waits up to 70 ms for the host to take the previous packet, so
 *    neither can be used to avoid blocking. While no host has the port open (DTR low, or USB not
 *    configured: battery power) frames are dropped at once and the queue is emptied. */
#ifndef RW_ARDUINO_SERIAL_LINK_H
#define RW_ARDUINO_SERIAL_LINK_H

#include <stddef.h>
#include <stdint.h>

extern "C" {
#include "rw_cobs.h"
#include "rw_cobs_deframer.h"
#include "rw_hal_link.h"
#include "rw_protocol.h"
}

/* Encoded frames awaiting the host: three of the longest. */
static const size_t RW_SERIAL_TX_BYTES = 3u * (RW_COBS_MAX_ENCODED(RW_MAX_FRAME_LEN) + 1u);
/* One USB full-speed bulk packet carries 64 bytes; 63 keeps every write a single short packet. */
static const size_t RW_SERIAL_PACKET_BYTES = 63u;

struct rw_arduino_serial_link {
    rw_cobs_deframer rx;   /* received bytes -> frames; counts good and bad frames */
    uint8_t tx[RW_SERIAL_TX_BYTES];
    size_t tx_len;
    uint8_t in_endpoint;   /* USB endpoint of the CDC bulk IN (found once USB is configured; 0 = not yet) */
    uint32_t frames_out;   /* frames queued for the host */
    uint32_t tx_dropped;   /* frames dropped: queue full or nobody listening */
};

/* Serial.begin (the baud rate means nothing on USB CDC), no read timeout; clears the link's state. */
void rw_arduino_serial_link_begin(rw_arduino_serial_link *link);

/* Once per loop: hands the next queued packet to USB if the IN bank is free (never waits). */
void rw_arduino_serial_link_service(rw_arduino_serial_link *link);

rw_hal_link rw_arduino_serial_link_hal(rw_arduino_serial_link *link);

#endif /* RW_ARDUINO_SERIAL_LINK_H */
