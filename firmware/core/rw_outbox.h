/* Outgoing frames for the peer, waiting for the link. The link sends at most one datagram per control
 * tick (WiFiNINA is slow: one SPI exchange per call). The ACK/NACK of a received frame goes out in the
 * tick that received it, straight to its sender; what follows (PARAM_VALUE), events and telemetry queue
 * here by priority: replies first, then events, then telemetry. When full, a new telemetry frame is dropped before
 * anything else; the drop counters tell the host. */
#ifndef RW_OUTBOX_H
#define RW_OUTBOX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_protocol.h"

#define RW_OUTBOX_SLOTS 12u

typedef enum {
    RW_OUTBOX_REPLY = 0,     /* PARAM_VALUE after an ACK */
    RW_OUTBOX_EVENT = 1,     /* to the peer */
    RW_OUTBOX_TELEMETRY = 2, /* to the peer */
    RW_OUTBOX_BURST = 3,     /* BURST_DATA to the peer: queued only into an empty outbox, sent after everything */
} rw_outbox_class;

typedef struct rw_outbox_slot {
    uint8_t bytes[RW_MAX_FRAME_LEN];
    uint8_t len;
    uint8_t cls;
    bool used;
    uint32_t order;
} rw_outbox_slot;

typedef struct rw_outbox {
    struct {
        rw_outbox_slot slots[RW_OUTBOX_SLOTS];
        uint32_t next_order;
        uint16_t dropped;
        uint8_t used; /* slots in use: an empty outbox is answered without a scan (every tick) */
    } state;
} rw_outbox;

void rw_outbox_reset(rw_outbox *o);
/* Queue a frame; returns false (and counts a drop) when no slot is left for it. */
bool rw_outbox_push(rw_outbox *o, rw_outbox_class cls, const uint8_t *frame, size_t len);
/* The same in two steps, so a frame can be encoded straight into its slot (no copy): reserve the slot a
 * frame of class cls would take (NULL, a drop counted, when there is none), write up to RW_MAX_FRAME_LEN
 * bytes into slot->bytes, then commit with the length. A commit with length 0 or over RW_MAX_FRAME_LEN
 * counts a drop and leaves the slot free (a displaced telemetry frame is lost either way). Nothing else
 * may touch the outbox between the two calls. */
rw_outbox_slot *rw_outbox_reserve(rw_outbox *o, rw_outbox_class cls);
bool rw_outbox_commit(rw_outbox *o, rw_outbox_slot *slot, rw_outbox_class cls, size_t len);
/* The next frame to send (highest priority, oldest first), or NULL; pop it after sending. */
const rw_outbox_slot *rw_outbox_peek(const rw_outbox *o);
void rw_outbox_pop(rw_outbox *o, const rw_outbox_slot *slot);
uint16_t rw_outbox_dropped(const rw_outbox *o);
/* Count a frame lost after it left the outbox (taken for signing, then void: a new session began). */
void rw_outbox_count_drop(rw_outbox *o);

#endif /* RW_OUTBOX_H */
