/*
 * rw_cobs_deframer.h - the USB serial link's receive side: a byte stream in, COBS frames out (rw_cobs.h).
 *
 * Bytes are fed one at a time as they arrive (any chunking); a 0x00 delimiter ends a frame. What a
 * delimiter ends:
 *   nothing (back-to-back delimiters)       skipped
 *   a well-formed frame                     decoded into the caller's buffer, its length returned
 *   malformed COBS, a frame that does not   handed on as one 0x00 byte: "not a frame", which the core refuses
 *   fit the caller's buffer, or a run of    (BAD_MAGIC, a NACK with the reason) and counts (rx_bad), so that
 *   more than RW_COBS_DEFRAMER_MAX_ENCODED  garbage on the cable is never silent; the receiver is back in
 *   bytes without a delimiter               step at the next delimiter
 * Both serial HALs (the board's USB CDC, the SIL's pseudo-terminal) use it, so they frame identically.
 *
 * Portable core module: no Arduino header, no heap, reads no clock.
 */
#ifndef RW_COBS_DEFRAMER_H
#define RW_COBS_DEFRAMER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_cobs.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Encoded bytes held while waiting for the delimiter: well over the longest encoded protocol frame, so any
 * frame the core could answer with a reason (OVERSIZE, BAD_LENGTH) reaches it. */
#define RW_COBS_DEFRAMER_MAX_ENCODED 256u

typedef struct rw_cobs_deframer {
    struct {
        uint8_t encoded[RW_COBS_DEFRAMER_MAX_ENCODED]; /* the frame being received, delimiter not yet seen */
        size_t len;
        bool overflow;     /* the frame being received outgrew the buffer: skipped to its delimiter */
        uint32_t frames;   /* well-formed frames handed on */
        uint32_t bad;      /* malformed or over-long frames handed on as "not a frame" */
    } state;
} rw_cobs_deframer;

/** Empty, counters at 0. */
void rw_cobs_deframer_reset(rw_cobs_deframer *d);
/**
 * One received byte. Returns 0 while no frame is complete; at a delimiter that ends a frame, the length of
 * what was written to out (cap bytes, >= 1): the decoded frame, or 1 (out[0] = 0x00) for a bad one.
 */
size_t rw_cobs_deframer_put(rw_cobs_deframer *d, uint8_t byte, uint8_t *out, size_t cap);
/** Frames handed on well-formed / as "not a frame", since reset. */
uint32_t rw_cobs_deframer_frames(const rw_cobs_deframer *d);
uint32_t rw_cobs_deframer_bad_frames(const rw_cobs_deframer *d);

#ifdef __cplusplus
}
#endif

#endif /* RW_COBS_DEFRAMER_H */
