#include "rw_signer.h"

#include <string.h>

static void put_le(uint8_t *p, uint64_t v, unsigned n)
{
    for (unsigned i = 0u; i < n; ++i) {
        p[i] = (uint8_t)(v >> (8u * i));
    }
}

void rw_signer_reset(rw_signer *s)
{
    memset(s, 0, sizeof *s);
}

bool rw_signer_busy(const rw_signer *s)
{
    return s->state.len != 0u;
}

bool rw_signer_load(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                    const uint8_t key[RW_KEY_LEN])
{
    /* what rw_frame_sign_begin accepts: an unsigned frame of a known message, its length from its header */
    if (rw_signer_busy(s) || frame == NULL || len < RW_FRAME_HEADER_LEN + RW_FRAME_CHECKSUM_LEN || frame[2] != 0u ||
        len != RW_FRAME_HEADER_LEN + (size_t)frame[6] + RW_FRAME_CHECKSUM_LEN ||
        len + RW_SIGNATURE_LEN > sizeof s->state.frame) {
        return false;
    }
    const rw_msg_info *info = rw_msg_info_find(frame[3]);
    if (info == NULL) {
        return false;
    }
    memcpy(s->state.frame, frame, len);
    put_le(s->state.frame + 4, seq, 2u);
    s->state.frame[2] = RW_FRAME_FLAG_SIGNED;
    put_le(s->state.frame + len, session_id, 4u);
    s->state.len = (uint8_t)len;
    s->state.fixed_blocks = (uint8_t)(RW_FRAME_SIGN_FIXED_LEN(len) / RW_SIPHASH_BLOCK_LEN);
    s->state.done_blocks = 0u;
    s->state.crc = 0xFFFFu;
    s->state.crc_done = 1u; /* the checksum covers the frame from byte 1 (after the magic) */
    s->state.crc_extra = info->crc_extra;
    s->state.checksum_set = false;
    s->state.seal_phase = 0u;
    rw_siphash_init(&s->state.mac, key);
    return true;
}

bool rw_signer_checksum_done(const rw_signer *s)
{
    return rw_signer_busy(s) && s->state.checksum_set;
}

size_t rw_signer_checksum(rw_signer *s, size_t max_chunks)
{
    if (!rw_signer_busy(s) || s->state.checksum_set) {
        return 0u;
    }
    const size_t body_len = (size_t)s->state.len - RW_FRAME_CHECKSUM_LEN;
    size_t chunks = 0u;
    while (chunks < max_chunks && !s->state.checksum_set) {
        size_t n = body_len - s->state.crc_done;
        n = n < RW_SIGNER_CRC_CHUNK_LEN ? n : RW_SIGNER_CRC_CHUNK_LEN;
        s->state.crc = rw_crc16_ccitt(s->state.crc, s->state.frame + s->state.crc_done, n);
        s->state.crc_done = (uint8_t)(s->state.crc_done + n);
        ++chunks;
        if (s->state.crc_done >= body_len) { /* the message's extra, then the checksum into the frame */
            uint8_t extra[2];
            put_le(extra, s->state.crc_extra, 2u);
            put_le(s->state.frame + body_len, rw_crc16_ccitt(s->state.crc, extra, 2u), 2u);
            s->state.checksum_set = true;
        }
    }
    return chunks;
}

size_t rw_signer_blocks_left(const rw_signer *s)
{
    return rw_signer_busy(s) ? (size_t)(s->state.fixed_blocks - s->state.done_blocks) : 0u;
}

size_t rw_signer_absorb(rw_signer *s, size_t max_blocks)
{
    if (!rw_signer_busy(s)) {
        return 0u;
    }
    /* before the checksum is written only the blocks wholly before it are final */
    const size_t ready = s->state.checksum_set ? s->state.fixed_blocks
                                               : ((size_t)s->state.len - RW_FRAME_CHECKSUM_LEN) / RW_SIPHASH_BLOCK_LEN;
    const size_t left = ready > s->state.done_blocks ? ready - s->state.done_blocks : 0u;
    const size_t n = left < max_blocks ? left : max_blocks;
    rw_siphash_absorb(&s->state.mac, s->state.frame + RW_SIPHASH_BLOCK_LEN * s->state.done_blocks, n);
    s->state.done_blocks = (uint8_t)(s->state.done_blocks + n);
    return n;
}

bool rw_signer_seal_counter(rw_signer *s, uint64_t counter)
{
    if (!rw_signer_checksum_done(s) || rw_signer_blocks_left(s) != 0u) {
        return false;
    }
    const size_t len = s->state.len;
    const size_t tagged_len = rw_frame_sign_counter(s->state.frame, len, counter);
    const size_t absorbed = RW_SIPHASH_BLOCK_LEN * (size_t)s->state.fixed_blocks;
    s->state.seal_mac = s->state.mac; /* the MAC before the counter is kept: a new counter seals again from it */
    rw_siphash_absorb(&s->state.seal_mac, s->state.frame + absorbed, (tagged_len - absorbed) / RW_SIPHASH_BLOCK_LEN);
    s->state.sealed_counter = counter;
    s->state.seal_phase = 1u;
    return true;
}

bool rw_signer_seal_last(rw_signer *s)
{
    if (!rw_signer_busy(s) || s->state.seal_phase != 1u) {
        return false;
    }
    const size_t tagged_len = RW_FRAME_SIGN_TAGGED_LEN((size_t)s->state.len);
    const size_t done = s->state.seal_mac.absorbed;
    rw_siphash_absorb_last(&s->state.seal_mac, s->state.frame + done, tagged_len - done);
    s->state.seal_phase = 3u;
    return true;
}

bool rw_signer_seal_tag(rw_signer *s)
{
    if (rw_signer_busy(s) && s->state.seal_phase == 1u) {
        (void)rw_signer_seal_last(s);
    }
    if (!rw_signer_busy(s) || s->state.seal_phase != 3u) {
        return false;
    }
    (void)rw_frame_sign_tag(s->state.frame, s->state.len, rw_siphash_finalize(&s->state.seal_mac));
    s->state.seal_phase = 2u;
    return true;
}

size_t rw_signer_seal(rw_signer *s, uint64_t counter, const uint8_t **out)
{
    *out = NULL;
    if (!rw_signer_seal_counter(s, counter) || !rw_signer_seal_tag(s)) {
        return 0u;
    }
    return rw_signer_sealed_frame(s, out);
}

bool rw_signer_sealing(const rw_signer *s)
{
    return rw_signer_busy(s) && (s->state.seal_phase == 1u || s->state.seal_phase == 3u);
}

bool rw_signer_last_absorbed(const rw_signer *s)
{
    return rw_signer_busy(s) && s->state.seal_phase == 3u;
}

bool rw_signer_sealed(const rw_signer *s)
{
    return rw_signer_busy(s) && s->state.seal_phase == 2u;
}

uint64_t rw_signer_sealed_counter(const rw_signer *s)
{
    return s->state.sealed_counter;
}

size_t rw_signer_sealed_frame(const rw_signer *s, const uint8_t **out)
{
    *out = rw_signer_sealed(s) ? s->state.frame : NULL;
    return *out != NULL ? (size_t)s->state.len + RW_SIGNATURE_LEN : 0u;
}

void rw_signer_sent(rw_signer *s)
{
    s->state.len = 0u;
    s->state.seal_phase = 0u;
}

bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN])
{
    if (!rw_signer_load(s, frame, len, seq, session_id, key)) {
        return false;
    }
    (void)rw_signer_checksum(s, RW_MAX_FRAME_LEN);
    return true;
}

size_t rw_signer_finish(rw_signer *s, uint64_t counter, const uint8_t **out)
{
    const size_t len = rw_signer_seal(s, counter, out);
    if (len != 0u) {
        rw_signer_sent(s);
    }
    return len;
}
