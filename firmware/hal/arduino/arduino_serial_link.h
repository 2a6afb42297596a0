/* USB serial link on the board: Arduino `Serial` (native USB CDC of the SAMD21), frames COBS-encoded with
 * a 0x00 delimiter (core/rw_cobs.h). Implements rw_hal_link (hal/rw_hal_link.h) for hal.serial, the
 * trusted link: provisioning (PROVISION_*) and unsigned commands from a host on the cable
 * (`wrangler provision --port /dev/ttyACM0 ...`).
 *
 * The tick never touches USB: its recv takes decoded frames from a queue, its send puts frames in another
 * (core/rw_frame_queue.h). The background loop (rw_arduino_serial_link_service) does the USB side, never
 * waiting:
 *  - receive: while the queue to the tick has room, received bytes are fed one at a time (Serial.read(), at
 *    most RW_SERIAL_RX_BYTES_PER_PASS a pass) to the COBS deframer (core/rw_cobs_deframer.h), which decodes each
 *    complete frame straight into the queue (a malformed one goes in as a single 0 byte, "not a frame", which
 *    the core refuses and counts);
 *  - send: one queued frame per pass is encoded with its delimiter into tx, or dropped (counted) if it does
 *    not fit; tx leaves in USB packets of at most 63 bytes, one whenever the CDC IN endpoint's bank is free
 *    (checked on the USB registers before each Serial.write). On this core Serial.availableForWrite() always
 *    answers 63 and Serial.write() waits up to 70 ms for the host to take the previous packet, so neither
 *    can be used to avoid blocking. While no host has the port open (DTR low, or USB not configured: battery
 *    power) frames are dropped at once and tx is emptied.
 *  - notes: rw_arduino_serial_link_note puts a line of text for a person at a terminal between frames
 *    ("rw: ...\n" and a 0x00 delimiter): a host's COBS reader drops it as one malformed frame. */
#ifndef RW_ARDUINO_SERIAL_LINK_H
#define RW_ARDUINO_SERIAL_LINK_H

#include <stddef.h>
#include <stdint.h>

extern "C" {
#include "rw_cobs.h"
#include "rw_cobs_deframer.h"
#include "rw_frame_queue.h"
#include "rw_hal_link.h"
#include "rw_protocol.h"
}

/* Received bytes fed to the deframer per background pass at most (about 0.1 ms of work). */
static const size_t RW_SERIAL_RX_BYTES_PER_PASS = 64u;
/* Encoded frames awaiting the host: three of the longest. */
static const size_t RW_SERIAL_TX_BYTES = 3u * (RW_COBS_MAX_ENCODED(RW_MAX_FRAME_LEN) + 1u);
/* One USB full-speed bulk packet carries 64 bytes; 63 keeps every write a single short packet. */
static const size_t RW_SERIAL_PACKET_BYTES = 63u;

struct rw_arduino_serial_link {
    rw_frame_queue rx_frames; /* background -> tick: decoded frames */
    rw_frame_queue tx_frames; /* tick -> background: frames to encode and send */
    /* background side */
    rw_cobs_deframer deframer; /* received bytes -> frames; counts good and bad frames */
    uint8_t tx[RW_SERIAL_TX_BYTES];
    size_t tx_len;
    uint8_t in_endpoint;   /* USB endpoint of the CDC bulk IN (found once USB is configured; 0 = not yet) */
    uint32_t frames_out;   /* frames encoded for the host */
    uint32_t tx_dropped;   /* frames or notes dropped: tx full or nobody listening */
};

/* Serial.begin (the baud rate means nothing on USB CDC), no read timeout; clears the link's state. */
void rw_arduino_serial_link_begin(rw_arduino_serial_link *link);
/* Background loop: at most one frame decoded and one encoded, one USB packet handed over (never waits). */
void rw_arduino_serial_link_service(rw_arduino_serial_link *link);
/* Background loop: a text line for a person at a terminal (dropped, counted, if tx has no room or nobody listens). */
void rw_arduino_serial_link_note(rw_arduino_serial_link *link, const char *text);

rw_hal_link rw_arduino_serial_link_hal(rw_arduino_serial_link *link);

#endif /* RW_ARDUINO_SERIAL_LINK_H */
