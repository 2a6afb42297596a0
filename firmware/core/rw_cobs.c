#include "rw_cobs.h"

size_t rw_cobs_encode(const uint8_t *in, size_t n, uint8_t *out, size_t cap)
{
    if (cap < RW_COBS_MAX_ENCODED(n)) {
        return 0u;
    }
    size_t code_at = 0u; /* where the current block's code byte goes */
    size_t o = 1u;
    uint8_t code = 1u;   /* 1 + bytes in the current block */
    for (size_t i = 0u; i < n; ++i) {
        if (in[i] != 0u) {
            out[o++] = in[i];
            ++code;
        }
        if (in[i] == 0u || code == 0xFFu) {
            out[code_at] = code;
            code_at = o++;
            code = 1u;
        }
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
