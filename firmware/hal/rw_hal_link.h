/* Datagram link to the host (WiFiNINA UDP on the board, a POSIX UDP socket in SIL).
 *
 * The core receives at most one datagram per tick and sends at most one. Replies to a datagram (ACK/NACK)
 * go back to its sender; telemetry and events go to the peer, the sender of the last datagram the core
 * found valid (accept_peer), so a malformed or forged datagram cannot redirect the telemetry. */
#ifndef RW_HAL_LINK_H
#define RW_HAL_LINK_H

#include <stddef.h>
#include <stdint.h>

typedef struct rw_hal_link {
    void *ctx;
    /* Copy the next received datagram into buf (at most cap bytes); returns its length, 0 if none.
     * A longer datagram is truncated to cap and reported as cap + 1 (the core's cap exceeds the longest
     * frame, so the decoder refuses it as it would the whole datagram).
     * An empty datagram reads as none (0), as WiFiNINA's parsePacket() reports it on the board. */
    size_t (*recv)(void *ctx, uint8_t *buf, size_t cap);
    /* Send a datagram to the sender of the last received one. */
    void (*reply)(void *ctx, const uint8_t *frame, size_t len);
    /* Make the sender of the last received datagram the peer for send(). */
    void (*accept_peer)(void *ctx);
    /* Send a datagram to the peer; does nothing while there is none. */
    void (*send)(void *ctx, const uint8_t *frame, size_t len);
} rw_hal_link;

#endif /* RW_HAL_LINK_H */
