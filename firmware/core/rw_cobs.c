#include "rw_cobs.h"

#include <stdbool.h>

size_t rw_cobs_encode(const uint8_t *in, size_t n, uint8_t *out, size_t cap)
{
    if (cap < RW_COBS_MAX_ENCODED(n)) {
        return 0u;
    }
    size_t code_at = 0u; /* where the current block's code byte goes */
    size_t o = 1u;
    uint8_t code = 1u;   /* 1 + bytes in the current block */
    bool full_block_closed = false; /* the last block ended at 254 data bytes, not at a zero */
    for (size_t i = 0u; i < n; ++i) {
        if (in[i] != 0u) {
            out[o++] = in[i];
            ++code;
        }
        full_block_closed = false;
        if (in[i] == 0u || code == 0xFFu) {
            full_block_closed = in[i] != 0u;
            out[code_at] = code;
            code_at = o++;
            code = 1u;
        }
    }
    if (full_block_closed) {
        return o - 1u; /* input ended with a full block: no empty block follows it */
    }
    out[code_at] = code;
    return o;
}

size_t rw_cobs_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap)
{
    size_t i = 0u, o = 0u;
    while (i < n) {
        uint8_t code = in[i++];
        if (code == 0u || i + (size_t)code - 1u > n) {
            return 0u;
        }
        for (uint8_t k = 1u; k < code; ++k) {
            if (in[i] == 0u || o >= cap) {
                return 0u;
            }
            out[o++] = in[i++];
        }
        if (code != 0xFFu && i < n) {
            if (o >= cap) {
                return 0u;
            }
            out[o++] = 0u;
        }
    }
    return o;
}
