/* A frame being signed for the WiFi peer, its MAC spread over control ticks.
 *
 * A SipHash-2-4 tag over a telemetry frame costs about 4,000 Cortex-M0+ cycles, most of a 10 % tick budget
 * at 1 kHz; so the core signs in steps, one step per idle tick (rw_core.h, schedule): begin (copy, seq,
 * signed flag, checksum, session id), absorb the blocks that do not depend on the counter a few at a time, then
 * finish: the counter is taken only now, when the frame is about to leave, so counters grow in the order
 * frames are sent (the host refuses a counter it has passed), whatever was signed in between (an ACK is
 * signed in one piece in the tick of its command). The seq is given at begin. The tag equals rw_frame_sign's.
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
        uint8_t frame[RW_MAX_FRAME_LEN];
        uint8_t len;          /* the unsigned frame's length; 0 when idle */
        uint8_t fixed_blocks; /* MAC blocks before the counter */
        uint8_t done_blocks;  /* of those, absorbed */
        rw_siphash mac;
    } state;
} rw_signer;

void rw_signer_reset(rw_signer *s);
bool rw_signer_busy(const rw_signer *s);
/* Take an unsigned frame (copied): its seq (the frame is numbered as it leaves), signed flag, checksum,
 * session id; the MAC starts under key. Returns false (and stays idle) for a frame rw_frame_sign would
 * refuse, or when busy. */
bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN]);
/* Absorb up to max_blocks more of the blocks before the counter; returns how many it absorbed. */
size_t rw_signer_absorb(rw_signer *s, size_t max_blocks);
/* Blocks still to absorb before rw_signer_finish may be called. */
size_t rw_signer_blocks_left(const rw_signer *s);
/* Append the counter, finish the MAC, append the tag; *out points at the signed frame (valid until the next
 * begin) and its length is returned. 0 (and *out NULL) when not busy or blocks are left. Idle afterwards. */
size_t rw_signer_finish(rw_signer *s, uint64_t counter, const uint8_t **out);

#endif /* RW_SIGNER_H */
