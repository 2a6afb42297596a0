#include "rw_siphash.h"

/* The state is kept as eight 32-bit words (v[2i] the low, v[2i+1] the high half of v_i): the Cortex-M0+ has
 * 32-bit registers and no 64-bit rotate. A rotation by 32 is a swap of the halves. */

/* Little-endian 32-bit word from bytes (any alignment). */
static inline uint32_t load_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

#if defined(__ARM_ARCH_6M__)
/* SipRounds hand-scheduled for ARMv6-M (Cortex-M0+): with the state as uint64_t (or as 32-bit halves in C) the
 * compiler spills most of every round to the stack, about 110-190 cycles a round; here the whole state stays in
 * registers, 54 cycles a round (bench/bench_tick_instructions.py measures it).
 *
 * A round is four half-steps, each on two state words a, b: a += b; b = ROTL64(b, n) ^ a (and a = ROTL64(a, 32)
 * after the first and the last):  A (v0, v1, 13)  B (v2, v3, 16)  C (v0, v3, 21)  D (v2, v1, 17).
 * A half-step needs its two words and two temporaries in low registers (the rotate of a pair by n < 32:
 * lo' = lo << n | hi >> (32 - n), hi' = hi << n | lo >> (32 - n), written into the temporaries; the old
 * registers of b become the next temporaries); the word not in use waits in r8..r11 (mov: 1 cycle).
 * Register plan at the top of a round (also at its end): v0 = r0:r1 (lo:hi), v1 = r2:r3, v3 = r4:r5,
 * v2 = r8:r9, free r6 r7. Comments: v2 in (r2:r3) = v2 moves into r2:r3. */
#define RW_SIP_ROUND_ASM \
        /* A: v0 += v1; v1 = ROTL(v1, 13) ^ v0 -> r6:r7; v0 = ROTL(v0, 32) -> r1:r0 */ \
        "adds r0, r0, r2\n\t" \
        "adcs r1, r3\n\t" \
        "lsls r6, r2, #13\n\t" \
        "lsrs r7, r3, #19\n\t" \
        "orrs r6, r7\n\t" \
        "lsls r7, r3, #13\n\t" \
        "lsrs r2, r2, #19\n\t" \
        "orrs r7, r2\n\t" \
        "eors r6, r0\n\t" \
        "eors r7, r1\n\t" \
        /* v2 in (r2:r3), v1 out (r8:r9) */ \
        "mov r2, r8\n\t" \
        "mov r3, r9\n\t" \
        "mov r8, r6\n\t" \
        "mov r9, r7\n\t" \
        /* B: v2 += v3; v3 = ROTL(v3, 16) ^ v2 -> r6:r7 */ \
        "adds r2, r2, r4\n\t" \
        "adcs r3, r5\n\t" \
        "lsls r6, r4, #16\n\t" \
        "lsrs r7, r5, #16\n\t" \
        "orrs r6, r7\n\t" \
        "lsls r7, r5, #16\n\t" \
        "lsrs r4, r4, #16\n\t" \
        "orrs r7, r4\n\t" \
        "eors r6, r2\n\t" \
        "eors r7, r3\n\t" \
        /* C: v0 (r1:r0) += v3; v3 = ROTL(v3, 21) ^ v0 -> r4:r5 */ \
        "adds r1, r1, r6\n\t" \
        "adcs r0, r7\n\t" \
        "lsls r4, r6, #21\n\t" \
        "lsrs r5, r7, #11\n\t" \
        "orrs r4, r5\n\t" \
        "lsls r5, r7, #21\n\t" \
        "lsrs r6, r6, #11\n\t" \
        "orrs r5, r6\n\t" \
        "eors r4, r1\n\t" \
        "eors r5, r0\n\t" \
        /* v0 out (r10:r11), v1 in (r6:r7) */ \
        "mov r10, r1\n\t" \
        "mov r11, r0\n\t" \
        "mov r6, r8\n\t" \
        "mov r7, r9\n\t" \
        /* D: v2 += v1; v1 = ROTL(v1, 17) ^ v2 -> r0:r1; v2 = ROTL(v2, 32) -> r3:r2 */ \
        "adds r2, r2, r6\n\t" \
        "adcs r3, r7\n\t" \
        "lsls r0, r6, #17\n\t" \
        "lsrs r1, r7, #15\n\t" \
        "orrs r0, r1\n\t" \
        "lsls r1, r7, #17\n\t" \
        "lsrs r6, r6, #15\n\t" \
        "orrs r1, r6\n\t" \
        "eors r0, r2\n\t" \
        "eors r1, r3\n\t" \
        /* back to the plan: v2 -> r8:r9, v1 -> r2:r3, v0 -> r0:r1 */ \
        "mov r8, r3\n\t" \
        "mov r9, r2\n\t" \
        "movs r2, r0\n\t" \
        "movs r3, r1\n\t" \
        "mov r0, r10\n\t" \
        "mov r1, r11\n\t"

/* Compress n_blocks (>= 1) blocks m[0 .. 2 n_blocks) (little-endian words: m[2k] the low half of block k; word
 * aligned) into w[8]: per block v3 ^= m; two rounds; v0 ^= m. The block pointer waits in r12, the blocks left
 * in lr, w on the stack. */
__attribute__((naked, noinline)) static void sip_compress_words(__attribute__((unused)) uint32_t w[8],
                                                                 __attribute__((unused)) const uint32_t *m,
                                                                 __attribute__((unused)) uint32_t n_blocks)
{
    __asm__ volatile(
        ".syntax unified\n\t"
        "push {r4, r5, r6, r7, lr}\n\t"
        "mov r4, r8\n\t"
        "mov r5, r9\n\t"
        "mov r6, r10\n\t"
        "mov r7, r11\n\t"
        "push {r0, r4, r5, r6, r7}\n\t" /* w at [sp] */
        "mov r12, r1\n\t"
        "mov lr, r2\n\t"
        "ldr r2, [r0, #16]\n\t"
        "mov r8, r2\n\t"
        "ldr r2, [r0, #20]\n\t"
        "mov r9, r2\n\t"
        "ldr r2, [r0, #8]\n\t"
        "ldr r3, [r0, #12]\n\t"
        "ldr r4, [r0, #24]\n\t"
        "ldr r5, [r0, #28]\n\t"
        "ldr r1, [r0, #4]\n\t"
        "ldr r0, [r0, #0]\n\t"
        "1:\n\t"
        "mov r6, r12\n\t" /* v3 ^= m */
        "ldr r7, [r6, #0]\n\t"
        "eors r4, r7\n\t"
        "ldr r7, [r6, #4]\n\t"
        "eors r5, r7\n\t"
        RW_SIP_ROUND_ASM
        RW_SIP_ROUND_ASM
        "mov r6, r12\n\t" /* v0 ^= m, next block */
        "ldr r7, [r6, #0]\n\t"
        "eors r0, r7\n\t"
        "ldr r7, [r6, #4]\n\t"
        "eors r1, r7\n\t"
        "adds r6, #8\n\t"
        "mov r12, r6\n\t"
        "mov r7, lr\n\t"
        "subs r7, #1\n\t"
        "mov lr, r7\n\t"
        "bne 1b\n\t"
        "pop {r6}\n\t" /* w */
        "str r0, [r6, #0]\n\t"
        "str r1, [r6, #4]\n\t"
        "str r2, [r6, #8]\n\t"
        "str r3, [r6, #12]\n\t"
        "mov r7, r8\n\t"
        "str r7, [r6, #16]\n\t"
        "mov r7, r9\n\t"
        "str r7, [r6, #20]\n\t"
        "str r4, [r6, #24]\n\t"
        "str r5, [r6, #28]\n\t"
        "pop {r4, r5, r6, r7}\n\t"
        "mov r8, r4\n\t"
        "mov r9, r5\n\t"
        "mov r10, r6\n\t"
        "mov r11, r7\n\t"
        "pop {r4, r5, r6, r7, pc}\n\t");
}
#undef RW_SIP_ROUND_ASM

/* Whole blocks data[0 .. 8 n_blocks) into w: straight from data when it is word aligned (the M0+ is
 * little-endian: an aligned word load is load_le32), else through an aligned copy, a few blocks at a time. */
static void compress(uint32_t w[8], const uint8_t *data, size_t n_blocks)
{
    if (n_blocks == 0u) {
        return;
    }
    if (((uintptr_t)data & 3u) == 0u) {
        sip_compress_words(w, (const uint32_t *)(const void *)data, (uint32_t)n_blocks);
        return;
    }
    uint32_t m[8];
    while (n_blocks > 0u) {
        const size_t n = n_blocks < 4u ? n_blocks : 4u;
        for (size_t k = 0u; k < 2u * n; ++k) {
            m[k] = load_le32(data + 4u * k);
        }
        sip_compress_words(w, m, (uint32_t)n);
        data += RW_SIPHASH_BLOCK_LEN * n;
        n_blocks -= n;
    }
}

/* The d = 4 finalization rounds: two blocks of zeros (v ^= 0 changes nothing). */
static void finalize_rounds(uint32_t w[8])
{
    static const uint32_t zeros[4] = { 0u, 0u, 0u, 0u };
    sip_compress_words(w, zeros, 2u);
}
#else
/* One half-step on state words a (= v_a) and b (= v_b): v_a += v_b; v_b = ROTL64(v_b, n) ^ v_a; then v_a =
 * ROTL64(v_a, 32) when swap_a. n in 1..31. */
#define SIP_HALF(w, a, b, n, swap_a)                                                                           \
    do {                                                                                                       \
        uint32_t alo = (w)[2 * (a)], ahi = (w)[2 * (a) + 1], blo = (w)[2 * (b)], bhi = (w)[2 * (b) + 1];       \
        const uint64_t sum = (((uint64_t)ahi << 32) | alo) + (((uint64_t)bhi << 32) | blo);                    \
        alo = (uint32_t)sum;                                                                                   \
        ahi = (uint32_t)(sum >> 32);                                                                           \
        const uint32_t rlo = (blo << (n)) | (bhi >> (32 - (n)));                                               \
        const uint32_t rhi = (bhi << (n)) | (blo >> (32 - (n)));                                               \
        (w)[2 * (b)] = rlo ^ alo;                                                                              \
        (w)[2 * (b) + 1] = rhi ^ ahi;                                                                          \
        (w)[2 * (a)] = (swap_a) ? ahi : alo;                                                                   \
        (w)[2 * (a) + 1] = (swap_a) ? alo : ahi;                                                               \
    } while (0)

/* `rounds` SipRounds: v0 += v1; v1 = ROTL(v1, 13) ^ v0; v0 = ROTL(v0, 32); v2 += v3; v3 = ROTL(v3, 16) ^ v2;
 * v0 += v3; v3 = ROTL(v3, 21) ^ v0; v2 += v1; v1 = ROTL(v1, 17) ^ v2; v2 = ROTL(v2, 32). */
static void sip_rounds(uint32_t w[8], uint32_t rounds)
{
    for (uint32_t r = 0u; r < rounds; ++r) {
        SIP_HALF(w, 0, 1, 13, 1);
        SIP_HALF(w, 2, 3, 16, 0);
        SIP_HALF(w, 0, 3, 21, 0);
        SIP_HALF(w, 2, 1, 17, 1);
    }
}

/* Whole blocks data[0 .. 8 n_blocks): per block v3 ^= m; c = 2 rounds; v0 ^= m. */
static void compress(uint32_t w[8], const uint8_t *data, size_t n_blocks)
{
    for (size_t i = 0u; i < n_blocks; ++i) {
        const uint32_t m_lo = load_le32(data + RW_SIPHASH_BLOCK_LEN * i);
        const uint32_t m_hi = load_le32(data + RW_SIPHASH_BLOCK_LEN * i + 4u);
        w[6] ^= m_lo;
        w[7] ^= m_hi;
        sip_rounds(w, 2u); /* c = 2 */
        w[0] ^= m_lo;
        w[1] ^= m_hi;
    }
}

static void finalize_rounds(uint32_t w[8])
{
    sip_rounds(w, 4u); /* d = 4 */
}
#endif

static void init_word(uint32_t w[2], uint32_t k_lo, uint32_t k_hi, uint64_t constant)
{
    w[0] = k_lo ^ (uint32_t)constant;
    w[1] = k_hi ^ (uint32_t)(constant >> 32);
}

void rw_siphash_init(rw_siphash *s, const uint8_t key[16])
{
    const uint32_t k0lo = load_le32(key), k0hi = load_le32(key + 4);
    const uint32_t k1lo = load_le32(key + 8), k1hi = load_le32(key + 12);
    init_word(&s->v[0], k0lo, k0hi, 0x736f6d6570736575ULL); /* "somepseu" */
    init_word(&s->v[2], k1lo, k1hi, 0x646f72616e646f6dULL); /* "dorandom" */
    init_word(&s->v[4], k0lo, k0hi, 0x6c7967656e657261ULL); /* "lygenera" */
    init_word(&s->v[6], k1lo, k1hi, 0x7465646279746573ULL); /* "tedbytes" */
    s->absorbed = 0u;
}

void rw_siphash_absorb(rw_siphash *s, const uint8_t *data, size_t n_blocks)
{
    compress(s->v, data, n_blocks);
    s->absorbed += RW_SIPHASH_BLOCK_LEN * n_blocks;
}

uint64_t rw_siphash_finish(rw_siphash *s, const uint8_t *data, size_t len)
{
    size_t whole = len / RW_SIPHASH_BLOCK_LEN;
    rw_siphash_absorb(s, data, whole);
    size_t rest = len - RW_SIPHASH_BLOCK_LEN * whole;
    size_t total = s->absorbed + rest;
    /* last block: the remaining bytes, zero padded, with the total length mod 256 in the top byte */
    _Alignas(4) uint8_t last[RW_SIPHASH_BLOCK_LEN] = { 0u, 0u, 0u, 0u, 0u, 0u, 0u, (uint8_t)(total & 0xFFu) };
    for (size_t i = 0u; i < rest; ++i) {
        last[i] = data[RW_SIPHASH_BLOCK_LEN * whole + i];
    }
    compress(s->v, last, 1u);
    s->v[4] ^= 0xFFu;
    finalize_rounds(s->v);
    const uint32_t lo = s->v[0] ^ s->v[2] ^ s->v[4] ^ s->v[6];
    const uint32_t hi = s->v[1] ^ s->v[3] ^ s->v[5] ^ s->v[7];
    return ((uint64_t)hi << 32) | lo;
}

uint64_t rw_siphash24(const uint8_t key[16], const uint8_t *data, size_t len)
{
    rw_siphash s;
    rw_siphash_init(&s, key);
    return rw_siphash_finish(&s, data, len);
}
