#include "rw_frame_queue.h"

#include <string.h>

/* Keeps the compiler from moving memory accesses across it (single core: ordering against an interrupt). */
#define RW_COMPILER_BARRIER() __asm__ __volatile__("" ::: "memory")

void rw_frame_queue_init(rw_frame_queue *q)
{
    memset(q, 0, sizeof *q);
}

rw_frame_queue_slot *rw_frame_queue_reserve(rw_frame_queue *q)
{
    const uint32_t head = q->head;
    if (head - q->tail >= RW_FRAME_QUEUE_SLOTS) {
        ++q->dropped;
        return NULL;
    }
    return &q->slots[head % RW_FRAME_QUEUE_SLOTS];
}

void rw_frame_queue_publish(rw_frame_queue *q)
{
    const uint32_t head = q->head;
    const rw_frame_queue_slot *slot = &q->slots[head % RW_FRAME_QUEUE_SLOTS];
    if (slot->len == RW_FRAME_QUEUE_OVERSIZE) {
        ++q->oversize;
    }
    ++q->pushed;
    RW_COMPILER_BARRIER();
    q->head = head + 1u;
    const uint32_t queued = head + 1u - q->tail;
    if (queued > q->high_water) {
        q->high_water = queued;
    }
}

bool rw_frame_queue_push(rw_frame_queue *q, const uint8_t *frame, size_t len, uint32_t addr, uint16_t port)
{
    rw_frame_queue_slot *slot = rw_frame_queue_reserve(q);
    if (slot == NULL) {
        return false;
    }
    const size_t n = len > RW_MAX_FRAME_LEN ? RW_MAX_FRAME_LEN : len;
    memcpy(slot->bytes, frame, n);
    slot->len = len > RW_MAX_FRAME_LEN ? (uint16_t)RW_FRAME_QUEUE_OVERSIZE : (uint16_t)len;
    slot->addr = addr;
    slot->port = port;
    rw_frame_queue_publish(q);
    return true;
}

const rw_frame_queue_slot *rw_frame_queue_peek(const rw_frame_queue *q)
{
    const uint32_t tail = q->tail;
    if (q->head == tail) {
        return NULL;
    }
    RW_COMPILER_BARRIER();
    return &q->slots[tail % RW_FRAME_QUEUE_SLOTS];
}

void rw_frame_queue_release(rw_frame_queue *q)
{
    const uint32_t tail = q->tail;
    if (q->head == tail) {
        return;
    }
    RW_COMPILER_BARRIER();
    q->tail = tail + 1u;
}
