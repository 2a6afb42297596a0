/* Golden protocol vectors through the C codec: each frame must decode to the expected result, msg_id and
 * seq; each valid frame must unpack to the golden field values and re-encode to the same bytes.
 * Every frame is copied into a heap buffer of exactly its length so AddressSanitizer catches over-reads.
 * Prints one line per failure and a closing "N passed, N failed" line; exit status 1 on any failure. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rw_protocol.h"
#include "rw_protocol_vectors.h"
#include "rw_siphash.h"

static int check_vector(size_t i)
{
    const rw_protocol_vector *v = &rw_protocol_vectors[i];
    uint8_t *buf = malloc(v->len ? v->len : 1u);
    if (buf == NULL) {
        return 0;
    }
    memcpy(buf, v->bytes, v->len);
    rw_frame frame;
    int result = rw_frame_decode(buf, v->len, &frame);
    int ok = 1;
    if (result != v->expect_result) {
        printf("FAIL %s: result %d, expected %d\n", v->name, result, v->expect_result);
        ok = 0;
    } else if (frame.msg_id != v->expect_msg_id || frame.seq != v->expect_seq) {
        printf("FAIL %s: msg_id %u seq %u, expected %u %u\n", v->name, frame.msg_id, frame.seq,
               v->expect_msg_id, v->expect_seq);
        ok = 0;
    } else if (result == RW_DECODE_OK) {
        int bad_fields = rw_protocol_vector_check_fields(i, frame.payload);
        uint8_t out[RW_MAX_FRAME_LEN];
        size_t n = rw_frame_encode(frame.msg_id, frame.seq, frame.payload, frame.payload_len, out, sizeof out);
        if (bad_fields != 0) {
            printf("FAIL %s: %d field(s) differ from the golden values\n", v->name, bad_fields);
            ok = 0;
        } else if (v->expect_tag_valid < 0 && (n != v->len || memcmp(out, v->bytes, n) != 0)) {
            printf("FAIL %s: re-encoding differs\n", v->name);
            ok = 0;
        } else if (v->expect_tag_valid >= 0) {
            int valid = rw_frame_tag_valid(&frame, rw_protocol_vector_key);
            if (valid != v->expect_tag_valid || frame.session_id != v->expect_session_id ||
                frame.counter != v->expect_counter) {
                printf("FAIL %s: tag valid %d session %u counter %llu\n", v->name, valid, (unsigned)frame.session_id,
                       (unsigned long long)frame.counter);
                ok = 0;
            } else if (valid) {
                /* signing the unsigned form again gives the same bytes */
                uint8_t again[RW_MAX_FRAME_LEN];
                size_t m = rw_frame_encode(frame.msg_id, frame.seq, frame.payload, frame.payload_len, again, sizeof again);
                m = rw_frame_sign(again, m, sizeof again, frame.session_id, frame.counter, rw_protocol_vector_key);
                if (m != v->len || memcmp(again, v->bytes, m) != 0) {
                    printf("FAIL %s: re-signing differs\n", v->name);
                    ok = 0;
                }
            }
        }
    }
    free(buf);
    return ok;
}

int main(void)
{
    unsigned passed = 0u, failed = 0u;
    for (size_t i = 0; i < RW_PROTOCOL_VECTOR_COUNT; ++i) {
        if (check_vector(i)) {
            ++passed;
        } else {
            ++failed;
        }
    }
    /* encoder refusals: unknown id, wrong payload size, short output buffer */
    uint8_t out[RW_MAX_FRAME_LEN];
    uint8_t payload[4] = { 0 };
    int refusals_ok = rw_frame_encode(200u, 1u, payload, 4u, out, sizeof out) == 0u &&
                      rw_frame_encode(RW_MSG_ID_SET_ROPE_SPEED, 1u, payload, 3u, out, sizeof out) == 0u &&
                      rw_frame_encode(RW_MSG_ID_SET_ROPE_SPEED, 1u, payload, 4u, out, 12u) == 0u &&
                      rw_frame_encode(RW_MSG_ID_SET_ROPE_SPEED, 1u, payload, 4u, out, 13u) == 13u;
    /* SipHash-2-4 reference vectors (key 00..0f; messages 00..len-1), from the algorithm's paper */
    uint8_t msg[64];
    for (unsigned i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)i;
    }
    refusals_ok = refusals_ok && rw_siphash24(rw_protocol_vector_key, msg, 0u) == 0x726fdb47dd0e0e31ULL &&
                  rw_siphash24(rw_protocol_vector_key, msg, 15u) == 0xa129ca6149be45e5ULL;
    if (refusals_ok) {
        ++passed;
    } else {
        printf("FAIL encoder_refusals\n");
        ++failed;
    }
    printf("%u passed, %u failed\n", passed, failed);
    return failed == 0u ? 0 : 1;
}
