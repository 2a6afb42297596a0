/* SipHash-2-4 (Aumasson and Bernstein, 2012): the keyed MAC of the link. 128-bit key, 64-bit tag.
 * Chosen over HMAC-SHA256 because it is built for short messages and costs a few thousand instructions
 * on a Cortex-M0+ instead of four SHA-256 blocks (bench/bench_tick_instructions.py measures it).
 *
 * Two ways in: rw_siphash24 (one call), or incremental (init, absorb whole 8-byte blocks as they become
 * known, finish with the rest), which gives the same tag and lets the core spread one MAC over several
 * control ticks (rw_signer.h). */
#ifndef RW_SIPHASH_H
#define RW_SIPHASH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define RW_SIPHASH_BLOCK_LEN 8u

typedef struct rw_siphash {
    uint32_t v[8];    /* the SipHash state words v0..v3 as 32-bit halves: v[2i] low, v[2i+1] high (rw_siphash.c) */
    size_t absorbed; /* message bytes absorbed so far (a whole number of blocks) */
} rw_siphash;

/* A fresh MAC under key[0..16). */
void rw_siphash_init(rw_siphash *s, const uint8_t key[16]);
/* Absorb n_blocks whole 8-byte blocks data[0 .. 8 n_blocks). */
void rw_siphash_absorb(rw_siphash *s, const uint8_t *data, size_t n_blocks);
/* Absorb the rest of the message, data[0..len) (any length, whole blocks included), and return the tag of
 * everything absorbed. The state is spent afterwards. */
uint64_t rw_siphash_finish(rw_siphash *s, const uint8_t *data, size_t len);

/* The tag of data[0..len) under key[0..16); the 8 tag bytes on the wire are this value little-endian. */
uint64_t rw_siphash24(const uint8_t key[16], const uint8_t *data, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* RW_SIPHASH_H */
