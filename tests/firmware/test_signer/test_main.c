/*
 * Unity tests of rw_signer (a frame signed in steps over control ticks): the signed bytes equal
 * rw_frame_sign's for every absorb budget and the counter given at finish; the seq is the one given at begin; the counter is the one taken at
 * finish, not at begin; finish is refused while blocks are left; begin is refused while busy and for frames
 * rw_frame_sign refuses (already signed, wrong length, unknown id); the frame decodes and its tag verifies,
 * and a flipped bit does not. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_protocol.h"
#include "rw_signer.h"

static const uint8_t key[RW_KEY_LEN] = { 9u, 8u, 7u, 6u, 5u, 4u, 3u, 2u, 1u, 0u, 11u, 12u, 13u, 14u, 15u, 16u };
static rw_signer signer;

void setUp(void)
{
    rw_signer_reset(&signer);
}

void tearDown(void) {}

static size_t telemetry_frame(uint8_t *out, uint16_t seq)
{
    rw_msg_telemetry t;
    memset(&t, 0, sizeof t);
    t.time_ms = 123456u;
    t.rope_speed_mmps = 5000u;
    t.esc_pulse_us = 1432u;
    t.guide_position_um = -42;
    return rw_msg_telemetry_encode(&t, seq, out, RW_MAX_FRAME_LEN);
}

static size_t ack_frame(uint8_t *out, uint16_t seq)
{
    rw_msg_ack a = { .cmd_msg_id = RW_MSG_ID_ARM, .cmd_seq = 7u, .state = RW_STATE_ARMED };
    return rw_msg_ack_encode(&a, seq, out, RW_MAX_FRAME_LEN);
}

/* Sign frame[0..n) with the signer, absorbing `budget` blocks per step; returns the signed length. */
static size_t sign_in_steps(const uint8_t *frame, size_t n, size_t budget, uint64_t counter, uint8_t *out)
{
    TEST_ASSERT_TRUE(rw_signer_begin(&signer, frame, n, 300u, 0x01020304u, key));
    TEST_ASSERT_TRUE(rw_signer_busy(&signer));
    unsigned steps = 0u;
    while (rw_signer_blocks_left(&signer) != 0u) {
        const uint8_t *none = NULL;
        TEST_ASSERT_EQUAL_UINT(0u, rw_signer_finish(&signer, counter, &none)); /* not yet */
        TEST_ASSERT_NULL(none);
        const size_t left = rw_signer_blocks_left(&signer);
        TEST_ASSERT_EQUAL_UINT(left < budget ? left : budget, rw_signer_absorb(&signer, budget));
        TEST_ASSERT_TRUE(++steps <= RW_MAX_FRAME_LEN);
    }
    const uint8_t *signed_frame = NULL;
    size_t len = rw_signer_finish(&signer, counter, &signed_frame);
    TEST_ASSERT_NOT_NULL(signed_frame);
    TEST_ASSERT_FALSE(rw_signer_busy(&signer));
    memcpy(out, signed_frame, len);
    return len;
}

/* rw_signer_begin_prepared (the MAC's initial state under the key, prepared once) signs the same bytes as
 * rw_frame_sign, one step at a time, for frames of every length class (the checksum is stored by the last step),
 * also with a source that is not word aligned (copied byte by byte). */
static void test_prepared_key_and_unaligned_source_give_rw_frame_sign_bytes(void)
{
    rw_siphash key_mac;
    rw_siphash_init(&key_mac, key);
    uint8_t buf[RW_MAX_FRAME_LEN + 1u];
    uint8_t ref[RW_MAX_FRAME_LEN];
    size_t (*const makers[])(uint8_t *, uint16_t) = { telemetry_frame, ack_frame };
    for (unsigned m = 0u; m < 2u; ++m) {
        for (unsigned offset = 0u; offset < 2u; ++offset) {
            uint8_t *frame = buf + offset;
            const size_t n = makers[m](frame, 300u);
            memcpy(ref, frame, n);
            const size_t ref_len = rw_frame_sign(ref, n, sizeof ref, 0x01020304u, 77u, key);
            rw_signer_reset(&signer);
            TEST_ASSERT_TRUE(rw_signer_begin_prepared(&signer, frame, n, 300u, 0x01020304u, &key_mac));
            while (rw_signer_blocks_left(&signer) != 0u) {
                TEST_ASSERT_EQUAL_UINT(1u, rw_signer_absorb(&signer, 1u));
            }
            const uint8_t *out = NULL;
            TEST_ASSERT_EQUAL_UINT(ref_len, rw_signer_finish(&signer, 77u, &out));
            TEST_ASSERT_EQUAL_UINT8_ARRAY(ref, out, ref_len);
        }
    }
}

static void test_steps_give_rw_frame_sign_bytes_for_every_budget(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    uint8_t ref[RW_MAX_FRAME_LEN];
    uint8_t got[RW_MAX_FRAME_LEN];
    size_t (*const makers[])(uint8_t *, uint16_t) = { telemetry_frame, ack_frame };
    for (unsigned m = 0u; m < 2u; ++m) {
        size_t n = makers[m](frame, 300u);
        TEST_ASSERT_TRUE(n > 0u);
        memcpy(ref, frame, n);
        size_t ref_len = rw_frame_sign(ref, n, sizeof ref, 0x01020304u, 0x1122334455667788ULL, key);
        TEST_ASSERT_EQUAL_UINT(n + RW_SIGNATURE_LEN, ref_len);
        for (size_t budget = 1u; budget <= 12u; ++budget) {
            size_t len = sign_in_steps(frame, n, budget, 0x1122334455667788ULL, got);
            TEST_ASSERT_EQUAL_UINT(ref_len, len);
            TEST_ASSERT_EQUAL_HEX8_ARRAY(ref, got, len);
        }
    }
}

static void test_the_counter_is_the_one_given_at_finish(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    uint8_t got[RW_MAX_FRAME_LEN];
    size_t n = telemetry_frame(frame, 1u);
    size_t len = sign_in_steps(frame, n, 3u, 777u, got);
    rw_frame f;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(got, len, &f));
    TEST_ASSERT_EQUAL_UINT32(0x01020304u, f.session_id);
    TEST_ASSERT_EQUAL_UINT16(300u, f.seq); /* the seq given at begin, not the one it was encoded with (1) */
    TEST_ASSERT_EQUAL_UINT64(777u, f.counter);
    TEST_ASSERT_TRUE(rw_frame_tag_valid(&f, key));
    got[10] ^= 0x10u; /* a payload bit flipped in transit: the checksum refuses the frame */
    TEST_ASSERT_NOT_EQUAL(RW_DECODE_OK, rw_frame_decode(got, len, &f));
}

static void test_a_tampered_counter_fails_the_tag(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    uint8_t got[RW_MAX_FRAME_LEN];
    size_t n = ack_frame(frame, 2u);
    size_t len = sign_in_steps(frame, n, 2u, 41u, got);
    got[n + 4u] ^= 0x01u; /* counter 41 -> 40: a replayer's edit */
    rw_frame f;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(got, len, &f));
    TEST_ASSERT_EQUAL_UINT64(40u, f.counter);
    TEST_ASSERT_FALSE(rw_frame_tag_valid(&f, key));
}

static void test_begin_refuses_when_busy_or_for_a_frame_sign_would_refuse(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    size_t n = ack_frame(frame, 3u);
    TEST_ASSERT_TRUE(rw_signer_begin(&signer, frame, n, 3u, 1u, key));
    TEST_ASSERT_FALSE(rw_signer_begin(&signer, frame, n, 3u, 1u, key)); /* busy */
    rw_signer_reset(&signer);
    TEST_ASSERT_FALSE(rw_signer_begin(&signer, frame, n - 1u, 3u, 1u, key)); /* length disagrees with the header */
    TEST_ASSERT_FALSE(rw_signer_busy(&signer));
    uint8_t again[RW_MAX_FRAME_LEN];
    memcpy(again, frame, n);
    size_t s = rw_frame_sign(again, n, sizeof again, 1u, 1u, key);
    TEST_ASSERT_FALSE(rw_signer_begin(&signer, again, s, 3u, 1u, key)); /* already signed */
    frame[3] = 0xEEu; /* no such message id */
    TEST_ASSERT_FALSE(rw_signer_begin(&signer, frame, n, 3u, 1u, key));
    TEST_ASSERT_FALSE(rw_signer_begin(&signer, NULL, n, 3u, 1u, key));
    TEST_ASSERT_FALSE(rw_signer_busy(&signer));
    const uint8_t *out = NULL;
    TEST_ASSERT_EQUAL_UINT(0u, rw_signer_finish(&signer, 1u, &out)); /* nothing to finish */
    TEST_ASSERT_NULL(out);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_steps_give_rw_frame_sign_bytes_for_every_budget);
    RUN_TEST(test_prepared_key_and_unaligned_source_give_rw_frame_sign_bytes);
    RUN_TEST(test_the_counter_is_the_one_given_at_finish);
    RUN_TEST(test_a_tampered_counter_fails_the_tag);
    RUN_TEST(test_begin_refuses_when_busy_or_for_a_frame_sign_would_refuse);
    return UNITY_END();
}
