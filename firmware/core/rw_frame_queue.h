/* Frames handed between the control tick and the board's background loop: one producer, one consumer.
 *
 * On the board the tick (an interrupt) never touches a bus: a link's receive side is a queue the background
 * loop fills from WiFiNINA or USB and the tick empties (rw_hal_link.recv), its send side a queue the tick
 * fills (reply, send) and the background loop empties onto the bus. Each slot carries one frame with an
 * address and port (the datagram's sender, or where it goes; 0 where the link has no addresses).
 *
 * A full queue refuses the frame and counts it (dropped): the producer never waits. A frame longer than a
 * slot is kept truncated and marked oversize (len = RW_FRAME_QUEUE_OVERSIZE), so that the receiving core
 * refuses it as it would the whole datagram.
 *
 * Concurrency: one producer and one consumer on a single core, either of which may interrupt the other
 * anywhere. The producer writes only head (and its slot before publishing it), the consumer only tail; a
 * compiler barrier orders the slot's bytes before the index that publishes or frees it. Indices are free
 * running 32-bit counters (head - tail = frames queued). Pure: no clock, no heap, no I/O. */
#ifndef RW_FRAME_QUEUE_H
#define RW_FRAME_QUEUE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_protocol.h"

#define RW_FRAME_QUEUE_SLOTS 4u
/* A slot holds the longest frame; len of a truncated (longer) frame. */
#define RW_FRAME_QUEUE_OVERSIZE (RW_MAX_FRAME_LEN + 1u)

typedef struct rw_frame_queue_slot {
    uint32_t addr;  /* IPv4 address (WiFi) or 0 */
    uint16_t port;  /* UDP port (WiFi) or 0 */
    uint16_t len;   /* bytes used, or RW_FRAME_QUEUE_OVERSIZE */
    uint8_t bytes[RW_MAX_FRAME_LEN];
} rw_frame_queue_slot;

typedef struct rw_frame_queue {
    rw_frame_queue_slot slots[RW_FRAME_QUEUE_SLOTS];
    volatile uint32_t head;  /* producer: frames published */
    volatile uint32_t tail;  /* consumer: frames released */
    uint32_t pushed;         /* producer: frames accepted */
    uint32_t dropped;        /* producer: frames refused, queue full */
    uint32_t oversize;       /* producer: frames truncated (longer than a slot) */
    uint32_t high_water;     /* producer: most frames ever queued at once */
} rw_frame_queue;

#ifdef __cplusplus
extern "C" {
#endif

void rw_frame_queue_init(rw_frame_queue *q);

/* Producer: the next free slot to fill in place (NULL when full: counted as dropped), then publish it. */
rw_frame_queue_slot *rw_frame_queue_reserve(rw_frame_queue *q);
void rw_frame_queue_publish(rw_frame_queue *q);
/* Producer: copy a frame in (a longer one is truncated and marked oversize); false when full (counted). */
bool rw_frame_queue_push(rw_frame_queue *q, const uint8_t *frame, size_t len, uint32_t addr, uint16_t port);

/* Consumer: the oldest frame (NULL when empty), then release it. */
const rw_frame_queue_slot *rw_frame_queue_peek(const rw_frame_queue *q);
void rw_frame_queue_release(rw_frame_queue *q);

static inline uint32_t rw_frame_queue_count(const rw_frame_queue *q)
{
    return q->head - q->tail;
}

#ifdef __cplusplus
}
#endif

#endif /* RW_FRAME_QUEUE_H */
