#include "rw_siphash.h"

static uint64_t load_le64(const uint8_t *p)
{
    uint64_t v = 0u;
    for (int i = 7; i >= 0; --i) {
        v = (v << 8) | p[i];
    }
    return v;
}

static uint64_t rotl(uint64_t x, unsigned b)
{
    return (x << b) | (x >> (64u - b));
}

/* One SipRound: the ARX permutation of the four state words. */
static void sip_round(uint64_t v[4])
{
    v[0] += v[1];
    v[1] = rotl(v[1], 13u) ^ v[0];
    v[0] = rotl(v[0], 32u);
    v[2] += v[3];
    v[3] = rotl(v[3], 16u) ^ v[2];
    v[0] += v[3];
    v[3] = rotl(v[3], 21u) ^ v[0];
    v[2] += v[1];
    v[1] = rotl(v[1], 17u) ^ v[2];
    v[2] = rotl(v[2], 32u);
}

static void compress(uint64_t v[4], uint64_t m)
{
    v[3] ^= m;
    sip_round(v);
    sip_round(v);
    v[0] ^= m;
}

uint64_t rw_siphash24(const uint8_t key[16], const uint8_t *data, size_t len)
{
    const uint64_t k0 = load_le64(key);
    const uint64_t k1 = load_le64(key + 8);
    uint64_t v[4] = {
        k0 ^ 0x736f6d6570736575ULL, /* "somepseu" */
        k1 ^ 0x646f72616e646f6dULL, /* "dorandom" */
        k0 ^ 0x6c7967656e657261ULL, /* "lygenera" */
        k1 ^ 0x7465646279746573ULL, /* "tedbytes" */
    };
    size_t whole = len & ~(size_t)7u;
    for (size_t i = 0; i < whole; i += 8u) {
        compress(v, load_le64(data + i));
    }
    /* last block: the remaining bytes, zero padded, with len mod 256 in the top byte */
    uint64_t last = (uint64_t)(len & 0xFFu) << 56;
    for (size_t i = 0; i < (len & 7u); ++i) {
        last |= (uint64_t)data[whole + i] << (8u * i);
    }
    compress(v, last);
    v[2] ^= 0xFFu;
    sip_round(v);
    sip_round(v);
    sip_round(v);
    sip_round(v);
    return v[0] ^ v[1] ^ v[2] ^ v[3];
}
