/* Fuzz target: the frame decoder, the tag check, every message's unpack and the signer, on arbitrary bytes.
 *
 * The input is copied into a heap buffer of exactly its size, so AddressSanitizer reports any read past
 * len. Invariants (a violation traps, libFuzzer keeps the input):
 *   - rw_frame_decode returns RW_DECODE_OK or a NACK reason (1..RW_NACK_REASON_COUNT-1); on OK the frame
 *     is exactly the input, msg_id is in the schema, payload points inside it;
 *   - a decoded frame's payload unpacks and re-encodes (same seq) to the same frame, byte for byte
 *     (text messages: to a frame that decodes);
 *   - rw_frame_tag_valid never accepts an unsigned frame; a frame signed here verifies with its key and
 *     with no other, and any one flipped bit of it is rejected (by the decoder or by the tag);
 *   - every message's unpack reads only its payload length (each from an exactly sized heap copy). */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_common.h"
#include "rw_protocol.h"

static const uint8_t KEY[RW_KEY_LEN] = { 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15 };
static const uint8_t OTHER_KEY[RW_KEY_LEN] = { 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0 };

static void check_sign_and_verify(const uint8_t *frame, size_t len, const rw_frame *decoded, const uint8_t *data,
                                  size_t size)
{
    /* sign a copy in an exactly sized buffer (cap = len + signature), as the core does on WiFi */
    size_t cap = len + RW_SIGNATURE_LEN;
    uint8_t *buf = malloc(cap);
    RW_FUZZ_REQUIRE(buf != NULL);
    memcpy(buf, frame, len);
    uint32_t session_id = (uint32_t)size * 2654435761u;
    uint64_t counter = ((uint64_t)decoded->seq << 32) | decoded->checksum;
    size_t signed_len = rw_frame_sign(buf, len, cap, session_id, counter, KEY);
    if ((decoded->flags & RW_FRAME_FLAG_SIGNED) != 0u) {
        RW_FUZZ_REQUIRE(signed_len == 0u); /* only an unsigned frame is signed */
        free(buf);
        return;
    }
    RW_FUZZ_REQUIRE(signed_len == cap);
    rw_frame s;
    RW_FUZZ_REQUIRE(rw_frame_decode(buf, signed_len, &s) == RW_DECODE_OK);
    RW_FUZZ_REQUIRE(s.msg_id == decoded->msg_id && s.seq == decoded->seq && s.session_id == session_id &&
                    s.counter == counter);
    RW_FUZZ_REQUIRE(memcmp(s.payload, decoded->payload, decoded->payload_len) == 0);
    RW_FUZZ_REQUIRE(rw_frame_tag_valid(&s, KEY) == 1);
    RW_FUZZ_REQUIRE(rw_frame_tag_valid(&s, OTHER_KEY) == 0);
    /* one flipped bit (position chosen by the input): never a frame that decodes and verifies */
    size_t bit = (size > 0u ? data[size - 1u] * 7u + size : 0u) % (signed_len * 8u);
    buf[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    rw_frame t;
    if (rw_frame_decode(buf, signed_len, &t) == RW_DECODE_OK) {
        RW_FUZZ_REQUIRE(rw_frame_tag_valid(&t, KEY) == 0);
    }
    free(buf);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t *buf = rw_fuzz_exact_copy(data, size);
    rw_frame frame;
    int result = rw_frame_decode(buf, size, &frame);
    RW_FUZZ_REQUIRE(result >= 0 && result < (int)RW_NACK_REASON_COUNT);
    /* unsigned frames are never accepted by the tag check, decoded or not */
    RW_FUZZ_REQUIRE(rw_frame_tag_valid(&frame, KEY) == 0 || (result == RW_DECODE_OK && frame.flags != 0u));
    if (result == RW_DECODE_OK) {
        const rw_msg_info *info = rw_msg_info_find(frame.msg_id);
        RW_FUZZ_REQUIRE(info != NULL && info->payload_len == frame.payload_len);
        RW_FUZZ_REQUIRE(frame.bytes == buf && frame.payload == buf + RW_FRAME_HEADER_LEN);
        size_t sig = (frame.flags & RW_FRAME_FLAG_SIGNED) != 0u ? RW_SIGNATURE_LEN : 0u;
        size_t unsigned_len = RW_FRAME_HEADER_LEN + (size_t)frame.payload_len + RW_FRAME_CHECKSUM_LEN;
        RW_FUZZ_REQUIRE(unsigned_len + sig == size && size <= RW_MAX_FRAME_LEN);
        (void)rw_frame_tag_valid(&frame, KEY);

        /* payload -> struct -> frame: the same frame (the unsigned part; text: a frame that decodes) */
        uint8_t out[RW_MAX_FRAME_LEN];
        size_t n = rw_fuzz_unpack_encode(frame.msg_id, frame.payload, frame.seq, out, sizeof out);
        RW_FUZZ_REQUIRE(n == unsigned_len);
        rw_frame again;
        RW_FUZZ_REQUIRE(rw_frame_decode(out, n, &again) == RW_DECODE_OK);
        if (!rw_fuzz_has_text(frame.msg_id)) {
            RW_FUZZ_REQUIRE(memcmp(out + RW_FRAME_HEADER_LEN, frame.payload, frame.payload_len) == 0);
            if (sig == 0u) {
                RW_FUZZ_REQUIRE(memcmp(out, buf, n) == 0);
            }
        }
        check_sign_and_verify(buf, size, &frame, data, size); /* a signed frame: refused */
    }
    free(buf);

    /* every message's unpack on the input's first payload_len bytes, from an exactly sized copy */
#define RW_FUZZ_UNPACK(lower, UPPER)                                        \
    if (size >= RW_MSG_##UPPER##_LEN) {                                     \
        uint8_t *p = rw_fuzz_exact_copy(data, RW_MSG_##UPPER##_LEN);        \
        rw_msg_##lower msg;                                                 \
        rw_msg_##lower##_unpack(&msg, p);                                   \
        uint8_t out[RW_MAX_FRAME_LEN];                                      \
        size_t n = rw_msg_##lower##_encode(&msg, 0u, out, sizeof out);      \
        RW_FUZZ_REQUIRE(n == RW_FRAME_HEADER_LEN + RW_MSG_##UPPER##_LEN + RW_FRAME_CHECKSUM_LEN); \
        free(p);                                                            \
    }
    RW_FUZZ_MESSAGES(RW_FUZZ_UNPACK)
#undef RW_FUZZ_UNPACK
    return 0;
}
