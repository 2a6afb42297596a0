#include "rw_siphash.h"

/* Little-endian 64-bit word from bytes, assembled as two 32-bit halves (a 64-bit shift per byte costs a
 * Cortex-M0+ several instructions; a 32-bit one costs one). */
static uint64_t load_le64(const uint8_t *p)
{
    uint32_t lo = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
    uint32_t hi = (uint32_t)p[4] | ((uint32_t)p[5] << 8) | ((uint32_t)p[6] << 16) | ((uint32_t)p[7] << 24);
    return ((uint64_t)hi << 32) | lo;
}

#define ROTL64(x, b) (((x) << (b)) | ((x) >> (64u - (b))))

/* The SipRound, the ARX permutation of the four state words, on locals (the compiler keeps what it can in
 * registers instead of going through the state array every round). */
#define SIP_ROUND()                                                                                            \
    do {                                                                                                       \
        v0 += v1;                                                                                              \
        v1 = ROTL64(v1, 13u) ^ v0;                                                                             \
        v0 = ROTL64(v0, 32u);                                                                                  \
        v2 += v3;                                                                                              \
        v3 = ROTL64(v3, 16u) ^ v2;                                                                             \
        v0 += v3;                                                                                              \
        v3 = ROTL64(v3, 21u) ^ v0;                                                                             \
        v2 += v1;                                                                                              \
        v1 = ROTL64(v1, 17u) ^ v2;                                                                             \
        v2 = ROTL64(v2, 32u);                                                                                  \
    } while (0)

/* Compress the blocks data[0 .. 8 n_blocks): c = 2 rounds each. */
static void compress(uint64_t v[4], const uint8_t *data, size_t n_blocks)
{
    uint64_t v0 = v[0], v1 = v[1], v2 = v[2], v3 = v[3];
    for (size_t i = 0u; i < n_blocks; ++i) {
        const uint64_t m = load_le64(data + RW_SIPHASH_BLOCK_LEN * i);
        v3 ^= m;
        SIP_ROUND();
        SIP_ROUND();
        v0 ^= m;
    }
    v[0] = v0;
    v[1] = v1;
    v[2] = v2;
    v[3] = v3;
}

void rw_siphash_init(rw_siphash *s, const uint8_t key[16])
{
    const uint64_t k0 = load_le64(key);
    const uint64_t k1 = load_le64(key + 8);
    s->v[0] = k0 ^ 0x736f6d6570736575ULL; /* "somepseu" */
    s->v[1] = k1 ^ 0x646f72616e646f6dULL; /* "dorandom" */
    s->v[2] = k0 ^ 0x6c7967656e657261ULL; /* "lygenera" */
    s->v[3] = k1 ^ 0x7465646279746573ULL; /* "tedbytes" */
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
    size_t total = s->absorbed + (len - RW_SIPHASH_BLOCK_LEN * whole);
    /* last block: the remaining bytes, zero padded, with the total length mod 256 in the top byte */
    uint8_t last[RW_SIPHASH_BLOCK_LEN] = { 0u, 0u, 0u, 0u, 0u, 0u, 0u, (uint8_t)(total & 0xFFu) };
    for (size_t i = 0u; i < len - RW_SIPHASH_BLOCK_LEN * whole; ++i) {
        last[i] = data[RW_SIPHASH_BLOCK_LEN * whole + i];
    }
    compress(s->v, last, 1u);
    uint64_t v0 = s->v[0], v1 = s->v[1], v2 = s->v[2] ^ 0xFFu, v3 = s->v[3];
    SIP_ROUND(); /* d = 4 finalization rounds */
    SIP_ROUND();
    SIP_ROUND();
    SIP_ROUND();
    return v0 ^ v1 ^ v2 ^ v3;
}

uint64_t rw_siphash24(const uint8_t key[16], const uint8_t *data, size_t len)
{
    rw_siphash s;
    rw_siphash_init(&s, key);
    return rw_siphash_finish(&s, data, len);
}
