#include "rw_outbox.h"

#include <string.h>

void rw_outbox_reset(rw_outbox *o)
{
    memset(o, 0, sizeof *o);
}

bool rw_outbox_push(rw_outbox *o, rw_outbox_class cls, const uint8_t *frame, size_t len)
{
    if (len == 0u || len > RW_MAX_FRAME_LEN) {
        ++o->state.dropped;
        return false;
    }
    rw_outbox_slot *free_slot = NULL;
    rw_outbox_slot *oldest_telemetry = NULL;
    for (unsigned i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        rw_outbox_slot *s = &o->state.slots[i];
        if (!s->used && free_slot == NULL) {
            free_slot = s;
        } else if (s->used && s->cls == RW_OUTBOX_TELEMETRY &&
                   (oldest_telemetry == NULL || s->order < oldest_telemetry->order)) {
            oldest_telemetry = s;
        }
    }
    if (free_slot == NULL && cls != RW_OUTBOX_TELEMETRY) {
        free_slot = oldest_telemetry; /* a reply or event displaces stale telemetry */
    }
    if (free_slot == NULL) {
        ++o->state.dropped;
        return false;
    }
    if (free_slot->used) {
        ++o->state.dropped;
    } else {
        ++o->state.used;
    }
    memcpy(free_slot->bytes, frame, len);
    free_slot->len = (uint8_t)len;
    free_slot->cls = (uint8_t)cls;
    free_slot->used = true;
    free_slot->order = o->state.next_order++;
    return true;
}

const rw_outbox_slot *rw_outbox_peek(const rw_outbox *o)
{
    const rw_outbox_slot *best = NULL;
    if (o->state.used == 0u) {
        return NULL;
    }
    for (unsigned i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        const rw_outbox_slot *s = &o->state.slots[i];
        if (s->used && (best == NULL || s->cls < best->cls || (s->cls == best->cls && s->order < best->order))) {
            best = s;
        }
    }
    return best;
}

void rw_outbox_pop(rw_outbox *o, const rw_outbox_slot *slot)
{
    for (unsigned i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
        if (&o->state.slots[i] == slot && o->state.slots[i].used) {
            o->state.slots[i].used = false;
            --o->state.used;
        }
    }
}

uint16_t rw_outbox_dropped(const rw_outbox *o)
{
    return o->state.dropped;
}
