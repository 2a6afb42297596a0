/* COBS (Consistent Overhead Byte Stuffing, Cheshire and Baker 1999): the USB serial framing. A frame is
 * COBS-encoded (no zero byte left in it) and followed by one 0x00 delimiter, so a receiver resynchronises
 * at the next zero after any garbage. Overhead: one byte per 254 plus the delimiter. */
#ifndef RW_COBS_H
#define RW_COBS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Largest encoded size of n bytes (without the delimiter). */
#define RW_COBS_MAX_ENCODED(n) ((n) + (n) / 254u + 1u)

/* Encode in[0..n) into out (cap bytes); returns the encoded length, 0 if it does not fit. */
size_t rw_cobs_encode(const uint8_t *in, size_t n, uint8_t *out, size_t cap);
/* Decode in[0..n) (one frame, delimiter removed) into out (cap bytes); returns the decoded length, or 0
 * for malformed input (a zero inside, a code running past the end) or one that does not fit. */
size_t rw_cobs_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap);

#ifdef __cplusplus
}
#endif

#endif /* RW_COBS_H */
