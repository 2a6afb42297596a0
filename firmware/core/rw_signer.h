/* A frame being signed for the WiFi peer, its MAC spread over control ticks.
 *
 * A signed TELEMETRY frame costs about 3,500 Cortex-M0+ cycles (its CRC-16 ~1,100, its SipHash-2-4 tag ~1,900,
 * the copy and the send the rest), more than a tick may spend beside its control work; so the core signs in
 * steps, a few a tick (rw_core.h, schedule): begin (copy, seq, signed flag, session id: no checksum), then
 * equal steps of one MAC block each, the frame's checksum computed alongside (each step checksums the next 8
 * bytes, so the block a step absorbs is final when it does), then finish: the counter is taken only now,
 * when the frame is about to leave, so counters grow in the order frames are sent (the host refuses a counter
 * it has passed), whatever was signed in between (an ACK is signed in one piece in the tick of its command).
 * The seq is given at begin. The signed frame equals rw_frame_sign's.
 */
#ifndef RW_SIGNER_H
#define RW_SIGNER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_protocol.h"
#include "rw_siphash.h"

typedef struct rw_signer {
    struct {
        uint8_t frame[RW_MAX_FRAME_LEN] __attribute__((aligned(4))); /* copied and absorbed by words */
        uint8_t len;          /* the unsigned frame's length; 0 when idle */
        uint8_t fixed_blocks; /* MAC blocks before the counter: the steps */
        uint8_t done_blocks;  /* of those, absorbed (steps done) */
        uint8_t crc_pos;      /* the next frame byte the checksum takes; the frame's length once it is stored */
        uint16_t crc;         /* the checksum so far (rw_crc16_ccitt over frame[1 .. crc_pos)) */
        uint16_t crc_extra;   /* the message's checksum constant */
        rw_siphash mac;
    } state;
} rw_signer;

void rw_signer_reset(rw_signer *s);
bool rw_signer_busy(const rw_signer *s);
/* Take an unsigned frame (copied): its seq (the frame is numbered as it leaves), signed flag, session id; the
 * MAC starts under key, the checksum is left to the steps. Returns false (and stays idle) for a frame
 * rw_frame_sign would refuse, or when busy. */
bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN]);
/* The same with the MAC's initial state under the key given (rw_siphash_init, done once for a key; copied). */
bool rw_signer_begin_prepared(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                              const rw_siphash *key_mac);
/* Up to max_blocks more steps: each checksums the next 8 bytes of the frame (the checksum is stored with the
 * last) and absorbs the next of the blocks before the counter; returns how many steps it did. */
size_t rw_signer_absorb(rw_signer *s, size_t max_blocks);
/* Steps (blocks) still to do before rw_signer_finish may be called. */
size_t rw_signer_blocks_left(const rw_signer *s);
/* Append the counter, finish the MAC, append the tag; *out points at the signed frame (valid until the next
 * begin) and its length is returned. 0 (and *out NULL) when not busy or blocks are left. Idle afterwards. */
size_t rw_signer_finish(rw_signer *s, uint64_t counter, const uint8_t **out);

#endif /* RW_SIGNER_H */
