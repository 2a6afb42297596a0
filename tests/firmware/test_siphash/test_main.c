/*
 * Unity tests of rw_siphash24 (SipHash-2-4, the link MAC): the reference tags of the SipHash paper
 * (Aumasson and Bernstein, 2012: key 00..0f, message 00..len-1; len 0 and the paper's 15-byte example),
 * more lengths computed with the Python siphash24 package (every tail length 0..7 and whole blocks), the
 * length byte in the last block (a zero appended changes the tag), every key bit and every message bit
 * changing the tag, the wire order of the tag bytes in a signed frame, and the incremental interface giving
 * the one-call tag for every split. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_protocol.h"
#include "rw_siphash.h"

static const uint8_t key[16] = { 0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u };
static uint8_t msg[64];

void setUp(void)
{
    for (unsigned i = 0u; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)i;
    }
}

void tearDown(void) {}

static void test_paper_vectors(void)
{
    TEST_ASSERT_EQUAL_HEX64(0x726fdb47dd0e0e31ULL, rw_siphash24(key, msg, 0u));
    TEST_ASSERT_EQUAL_HEX64(0xa129ca6149be45e5ULL, rw_siphash24(key, msg, 15u));
}

/* key 00..0f, message 00..len-1; tags from the Python siphash24 package (digest() read little-endian). */
static void test_more_lengths_match_the_python_package(void)
{
    static const struct {
        size_t len;
        uint64_t tag;
    } vectors[] = {
        { 1u, 0x74f839c593dc67fdULL },  { 7u, 0xab0200f58b01d137ULL },  { 8u, 0x93f5f5799a932462ULL },
        { 9u, 0x9e0082df0ba9e4b0ULL },  { 16u, 0x3f2acc7f57c29bdbULL }, { 17u, 0x699ae9f52cbe4794ULL },
        { 24u, 0xb8ad50c6f649af94ULL }, { 31u, 0x32d892fad841c342ULL }, { 32u, 0x7127512f72f27cceULL },
        { 63u, 0x958a324ceb064572ULL }, { 64u, 0xacd2c40b8502cad8ULL },
    };
    for (unsigned i = 0u; i < sizeof vectors / sizeof vectors[0]; ++i) {
        TEST_ASSERT_EQUAL_HEX64_MESSAGE(vectors[i].tag, rw_siphash24(key, msg, vectors[i].len), "length");
    }
}

static void test_trailing_zero_byte_changes_the_tag(void)
{
    uint8_t a[8] = { 1u, 2u, 3u, 0u, 0u, 0u, 0u, 0u };
    /* the same bytes zero padded: only the length byte of the last block tells them apart */
    TEST_ASSERT_NOT_EQUAL(rw_siphash24(key, a, 3u), rw_siphash24(key, a, 4u));
    TEST_ASSERT_NOT_EQUAL(rw_siphash24(key, a, 7u), rw_siphash24(key, a, 8u));
}

static void test_every_key_bit_and_message_bit_changes_the_tag(void)
{
    const uint64_t ref = rw_siphash24(key, msg, 25u);
    for (unsigned bit = 0u; bit < 128u; ++bit) {
        uint8_t k[16];
        memcpy(k, key, sizeof k);
        k[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        TEST_ASSERT_TRUE_MESSAGE(rw_siphash24(k, msg, 25u) != ref, "key bit");
    }
    for (unsigned bit = 0u; bit < 25u * 8u; ++bit) {
        msg[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        TEST_ASSERT_TRUE_MESSAGE(rw_siphash24(key, msg, 25u) != ref, "message bit");
        msg[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    }
    TEST_ASSERT_EQUAL_HEX64(ref, rw_siphash24(key, msg, 25u));
}

/* A signed frame ends with the tag of everything before it, little-endian. */
static void test_signed_frame_carries_the_tag_little_endian(void)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    rw_msg_arm arm = { 0u };
    size_t n = rw_msg_arm_encode(&arm, 7u, frame, sizeof frame);
    size_t s = rw_frame_sign(frame, n, sizeof frame, 3u, 0x0102030405060708ULL, key);
    TEST_ASSERT_EQUAL_UINT(n + RW_SIGNATURE_LEN, s);
    uint64_t tag = rw_siphash24(key, frame, s - 8u);
    for (unsigned i = 0u; i < 8u; ++i) {
        TEST_ASSERT_EQUAL_HEX8((uint8_t)(tag >> (8u * i)), frame[s - 8u + i]);
    }
    rw_frame f;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(frame, s, &f));
    TEST_ASSERT_TRUE(rw_frame_tag_valid(&f, key));
    frame[s - 1u] ^= 1u;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(frame, s, &f));
    TEST_ASSERT_FALSE(rw_frame_tag_valid(&f, key));
}

/* Incremental (init, absorb whole blocks in any split, finish with the rest) gives the one-call tag. */
static void test_incremental_gives_the_same_tag_for_every_split(void)
{
    for (size_t len = 0u; len <= sizeof msg; ++len) {
        const uint64_t ref = rw_siphash24(key, msg, len);
        for (size_t first = 0u; first <= len / RW_SIPHASH_BLOCK_LEN; ++first) {
            rw_siphash s;
            rw_siphash_init(&s, key);
            rw_siphash_absorb(&s, msg, first);
            size_t done = RW_SIPHASH_BLOCK_LEN * first;
            TEST_ASSERT_EQUAL_HEX64_MESSAGE(ref, rw_siphash_finish(&s, msg + done, len - done), "split");
        }
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_incremental_gives_the_same_tag_for_every_split);
    RUN_TEST(test_paper_vectors);
    RUN_TEST(test_more_lengths_match_the_python_package);
    RUN_TEST(test_trailing_zero_byte_changes_the_tag);
    RUN_TEST(test_every_key_bit_and_message_bit_changes_the_tag);
    RUN_TEST(test_signed_frame_carries_the_tag_little_endian);
    return UNITY_END();
}
