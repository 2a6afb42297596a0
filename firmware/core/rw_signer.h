/* A frame being signed for the WiFi peer, its work spread over control ticks in small steps.
 *
 * Signing a 64-byte-payload frame (TELEMETRY, BURST_DATA) costs about 4,000 Cortex-M0+ cycles in all (the frame
 * checksum, eleven SipHash blocks, the finalization, the send): more than a tick's budget beside its other work
 * (rw_core.h). So the core signs in steps, each of a few hundred cycles, done with what a tick has left:
 *   load      copy an unsigned frame, set its seq (given now: the frame is numbered as it leaves), the signed
 *             flag and the session id; the MAC starts under the key
 *   checksum  the frame's CRC (it covers seq and flag), RW_SIGNER_CRC_CHUNK_LEN bytes a step
 *   absorb    the MAC blocks before the counter, a few a step (those before the checksum may go before it)
 *   seal      the counter, the last blocks, the finalization: the tag. The counter must grow in the order
 *             frames are sent (the host refuses a counter it has passed): seal takes the counter the frame
 *             will have if nothing else is signed before it is sent; if something is (an ACK signed at once in
 *             the tick of its command), the frame is sealed again with a new counter from the MAC state kept
 *             before the counter (no block is absorbed twice)
 *   send      the caller sends the sealed frame and calls rw_signer_sent.
 * The tag equals rw_frame_sign's (tests/firmware/test_signer). Pure: no clock, no heap. */
#ifndef RW_SIGNER_H
#define RW_SIGNER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_protocol.h"
#include "rw_siphash.h"

/* Checksum bytes a step. */
#define RW_SIGNER_CRC_CHUNK_LEN 16u

typedef struct rw_signer {
    struct {
        _Alignas(4) uint8_t frame[RW_MAX_FRAME_LEN]; /* word aligned: the MAC reads whole words (rw_siphash.c) */
        uint8_t len;          /* the unsigned frame's length; 0 when idle */
        uint8_t fixed_blocks; /* MAC blocks before the counter */
        uint8_t done_blocks;  /* of those, absorbed */
        uint8_t crc_done;     /* frame bytes [1, crc_done) are in crc */
        bool checksum_set;    /* the checksum is written */
        uint8_t seal_phase;   /* 0: not sealing; 1: counter written, its whole blocks in seal_mac; 3: the last block
                                 too; 2: sealed (tag written) */
        uint16_t crc;         /* the frame checksum so far */
        uint16_t crc_extra;   /* the message's checksum extra (rw_msg_info) */
        uint64_t sealed_counter;
        rw_siphash mac;       /* the MAC after the absorbed blocks (before the counter) */
        rw_siphash seal_mac;  /* mac continued over the counter's whole blocks (seal phase 1) */
    } state;
} rw_signer;

void rw_signer_reset(rw_signer *s);
bool rw_signer_busy(const rw_signer *s);
/* Take an unsigned frame (copied), with its seq, for session_id under key. Returns false (and stays idle) for a
 * frame rw_frame_sign would refuse (already signed, wrong length, unknown message), or when busy. */
bool rw_signer_load(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                    const uint8_t key[RW_KEY_LEN]);
/* Advance the checksum by up to max_chunks chunks of RW_SIGNER_CRC_CHUNK_LEN bytes; returns the chunks used. */
size_t rw_signer_checksum(rw_signer *s, size_t max_chunks);
/* The checksum is written (absorb may then take every block). */
bool rw_signer_checksum_done(const rw_signer *s);
/* Absorb up to max_blocks more of the blocks before the counter (only those the checksum does not touch until
 * it is written); returns how many it absorbed. */
size_t rw_signer_absorb(rw_signer *s, size_t max_blocks);
/* Blocks still to absorb before rw_signer_seal may be called. */
size_t rw_signer_blocks_left(const rw_signer *s);
/* Seal for counter in three steps: rw_signer_seal_counter writes the counter and absorbs its whole blocks into a
 * copy of the MAC (false when not busy, the checksum is not written or blocks are left); rw_signer_seal_last
 * absorbs the padded last block (false unless the counter step was done); rw_signer_seal_tag runs the
 * finalization and writes the tag (doing rw_signer_seal_last first if it was not; false unless the counter step
 * was done). Any time before the send it may start over with another counter: rw_signer_seal_counter again (the
 * MAC before the counter is kept). */
bool rw_signer_seal_counter(rw_signer *s, uint64_t counter);
bool rw_signer_seal_last(rw_signer *s);
bool rw_signer_seal_tag(rw_signer *s);
/* The last block is absorbed, the tag not yet written. */
bool rw_signer_last_absorbed(const rw_signer *s);
/* Both steps: the signed length (the frame at *out, valid until the next load), or 0 (*out NULL) when it
 * cannot seal. */
size_t rw_signer_seal(rw_signer *s, uint64_t counter, const uint8_t **out);
/* The counter step is done (for rw_signer_sealed_counter), the tag not yet written. */
bool rw_signer_sealing(const rw_signer *s);
bool rw_signer_sealed(const rw_signer *s);
uint64_t rw_signer_sealed_counter(const rw_signer *s);
/* The sealed frame (*out) and its signed length; 0 (*out NULL) when not sealed. */
size_t rw_signer_sealed_frame(const rw_signer *s, const uint8_t **out);
/* The sealed frame was sent: idle again. */
void rw_signer_sent(rw_signer *s);
/* All the steps at once, for one frame: load, checksum, absorb. Returns false as load does. */
bool rw_signer_begin(rw_signer *s, const uint8_t *frame, size_t len, uint16_t seq, uint32_t session_id,
                     const uint8_t key[RW_KEY_LEN]);
/* Seal for counter and be idle: the signed length and *out as rw_signer_seal (0 when it cannot seal). */
size_t rw_signer_finish(rw_signer *s, uint64_t counter, const uint8_t **out);

#endif /* RW_SIGNER_H */
