#include "rw_signer.h"

#include <string.h>

void rw_signer_reset(rw_signer *s)
{
    memset(s, 0, sizeof *s);
}

bool rw_signer_busy(const rw_signer *s)
{
    return s->state.len != 0u;
}

bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN])
{
    if (rw_signer_busy(s) || frame == NULL || len == 0u || len + RW_SIGNATURE_LEN > sizeof s->state.frame) {
        return false;
    }
    memcpy(s->state.frame, frame, len);
    if (rw_frame_sign_begin(s->state.frame, len, sizeof s->state.frame, seq, session_id) == 0u) {
        return false;
    }
    s->state.len = (uint8_t)len;
    s->state.fixed_blocks = (uint8_t)(RW_FRAME_SIGN_FIXED_LEN(len) / RW_SIPHASH_BLOCK_LEN);
    s->state.done_blocks = 0u;
    rw_siphash_init(&s->state.mac, key);
    return true;
}

size_t rw_signer_blocks_left(const rw_signer *s)
{
    return rw_signer_busy(s) ? (size_t)(s->state.fixed_blocks - s->state.done_blocks) : 0u;
}

size_t rw_signer_absorb(rw_signer *s, size_t max_blocks)
{
    size_t left = rw_signer_blocks_left(s);
    size_t n = left < max_blocks ? left : max_blocks;
    rw_siphash_absorb(&s->state.mac, s->state.frame + RW_SIPHASH_BLOCK_LEN * s->state.done_blocks, n);
    s->state.done_blocks = (uint8_t)(s->state.done_blocks + n);
    return n;
}

size_t rw_signer_finish(rw_signer *s, uint64_t counter, const uint8_t **out)
{
    *out = NULL;
    if (!rw_signer_busy(s) || rw_signer_blocks_left(s) != 0u) {
        return 0u;
    }
    size_t len = s->state.len;
    size_t tagged_len = rw_frame_sign_counter(s->state.frame, len, counter);
    size_t absorbed = RW_SIPHASH_BLOCK_LEN * (size_t)s->state.fixed_blocks;
    uint64_t tag = rw_siphash_finish(&s->state.mac, s->state.frame + absorbed, tagged_len - absorbed);
    size_t signed_len = rw_frame_sign_tag(s->state.frame, len, tag);
    s->state.len = 0u;
    *out = s->state.frame;
    return signed_len;
}
