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

/* memcpy into the (word-aligned) frame buffer, by words when the source is word aligned too (an outbox slot
 * is): the Cortex-M0+ newlib memcpy copies byte by byte, ~6 cycles a byte, a third of a tick's signing. */
static void copy_frame(uint8_t *dst, const uint8_t *src, size_t len)
{
    if (((uintptr_t)src & 3u) != 0u) {
        memcpy(dst, src, len);
        return;
    }
    const size_t words = len / 4u;
    uint32_t *d = (uint32_t *)(void *)dst;
    const uint32_t *w = (const uint32_t *)(const void *)src;
    for (size_t i = 0u; i < words; ++i) {
        d[i] = w[i];
    }
    for (size_t i = 4u * words; i < len; ++i) {
        dst[i] = src[i];
    }
}

bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN])
{
    rw_siphash init;
    rw_siphash_init(&init, key);
    return rw_signer_begin_prepared(s, frame, len, seq, session_id, &init);
}

bool rw_signer_begin_prepared(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                              const rw_siphash *key_mac)
{
    if (rw_signer_busy(s) || frame == NULL || len == 0u || len + RW_SIGNATURE_LEN > sizeof s->state.frame) {
        return false;
    }
    copy_frame(s->state.frame, frame, len);
    uint16_t crc_extra = 0u;
    if (rw_frame_sign_open(s->state.frame, len, sizeof s->state.frame, seq, session_id, &crc_extra) == 0u) {
        return false;
    }
    s->state.len = (uint8_t)len;
    s->state.fixed_blocks = (uint8_t)(RW_FRAME_SIGN_FIXED_LEN(len) / RW_SIPHASH_BLOCK_LEN);
    s->state.done_blocks = 0u;
    s->state.crc_pos = 1u; /* the checksum starts after the magic byte */
    s->state.crc = 0xFFFFu;
    s->state.crc_extra = crc_extra;
    s->state.mac = *key_mac;
    return true;
}

size_t rw_signer_blocks_left(const rw_signer *s)
{
    return rw_signer_busy(s) ? (size_t)(s->state.fixed_blocks - s->state.done_blocks) : 0u;
}

/* Step k checksums frame[1 + 8k .. 9 + 8k) (up to the checksum's place, then closes and stores it) and absorbs
 * block k, frame[8k .. 8k + 8): its bytes are all final then. The checksum needs ceil((len - 3) / 8) steps, the
 * blocks before the counter floor((len + 4) / 8): the same number, so the steps are equal. */
size_t rw_signer_absorb(rw_signer *s, size_t max_blocks)
{
    const size_t left = (size_t)(s->state.fixed_blocks - s->state.done_blocks); /* 0 when idle (reset) */
    size_t n = left < max_blocks ? left : max_blocks;
    if (n == 0u) {
        return 0u;
    }
    const size_t len = s->state.len;
    const size_t body_len = len - RW_FRAME_CHECKSUM_LEN;
    size_t pos = s->state.crc_pos;
    if (pos < body_len) {
        size_t end = pos + RW_SIPHASH_BLOCK_LEN * n;
        end = end < body_len ? end : body_len;
        s->state.crc = rw_crc16_ccitt(s->state.crc, s->state.frame + pos, end - pos);
        if (end == body_len) {
            rw_frame_checksum_put(s->state.frame, len, s->state.crc, s->state.crc_extra);
            end = len;
        }
        s->state.crc_pos = (uint8_t)end;
    }
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
