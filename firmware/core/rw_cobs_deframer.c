/*
 * rw_cobs_deframer.c - COBS stream deframer.
 */
#include "rw_cobs_deframer.h"

#include <string.h>

void rw_cobs_deframer_reset(rw_cobs_deframer *d)
{
    memset(d, 0, sizeof *d);
}

size_t rw_cobs_deframer_put(rw_cobs_deframer *d, uint8_t byte, uint8_t *out, size_t cap)
{
    if (byte != 0u) {
        if (d->state.len < RW_COBS_DEFRAMER_MAX_ENCODED) {
            d->state.encoded[d->state.len++] = byte;
        } else {
            d->state.overflow = true; /* dropped up to the delimiter */
        }
        return 0u;
    }
    const size_t n = d->state.len;
    const bool overflow = d->state.overflow;
    d->state.len = 0u;
    d->state.overflow = false;
    if (n == 0u && !overflow) {
        return 0u; /* back-to-back delimiters */
    }
    if (out == NULL || cap == 0u) {
        ++d->state.bad;
        return 0u; /* nowhere to put even the "not a frame" byte */
    }
    const size_t len = overflow ? 0u : rw_cobs_decode(d->state.encoded, n, out, cap);
    if (len == 0u) {
        ++d->state.bad;
        out[0] = 0u; /* not a frame: the core refuses it (BAD_MAGIC) and counts it */
        return 1u;
    }
    ++d->state.frames;
    return len;
}

uint32_t rw_cobs_deframer_frames(const rw_cobs_deframer *d)
{
    return d->state.frames;
}

uint32_t rw_cobs_deframer_bad_frames(const rw_cobs_deframer *d)
{
    return d->state.bad;
}
