/* SipHash-2-4 (Aumasson and Bernstein, 2012): the keyed MAC of the link. 128-bit key, 64-bit tag.
 * Chosen over HMAC-SHA256 because it is built for short messages and costs a few thousand instructions
 * on a Cortex-M0+ instead of four SHA-256 blocks (bench/bench_tick_instructions.py measures it). */
#ifndef RW_SIPHASH_H
#define RW_SIPHASH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The tag of data[0..len) under key[0..16); the 8 tag bytes on the wire are this value little-endian. */
uint64_t rw_siphash24(const uint8_t key[16], const uint8_t *data, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* RW_SIPHASH_H */
