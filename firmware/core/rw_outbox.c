#include "rw_outbox.h"

#include <string.h>

void rw_outbox_reset(rw_outbox *o)
{
    memset(o, 0, sizeof *o);
}

/* The slot a frame of class cls takes: a free one, else (replies and events) the oldest telemetry. */
static rw_outbox_slot *slot_for(rw_outbox *o, rw_outbox_class cls)
{
    if (o->state.used < RW_OUTBOX_SLOTS) { /* the first free one (the usual case: no scan of the rest) */
        for (unsigned i = 0u; i < RW_OUTBOX_SLOTS; ++i) {
            if (!o->state.slots[i].used) {
                return &o->state.slots[i];
            }
        }
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
    return free_slot;
}

rw_outbox_slot *rw_outbox_reserve(rw_outbox *o, rw_outbox_class cls)
{
    rw_outbox_slot *slot = slot_for(o, cls);
    if (slot == NULL) {
        ++o->state.dropped;
    }
    return slot;
}

bool rw_outbox_commit(rw_outbox *o, rw_outbox_slot *slot, rw_outbox_class cls, size_t len)
{
    if (len == 0u || len > RW_MAX_FRAME_LEN) {
        ++o->state.dropped;
        if (slot->used) { /* its old frame was overwritten */
            slot->used = false;
            --o->state.used;
        }
        return false;
    }
    if (slot->used) {
        ++o->state.dropped;
    } else {
        ++o->state.used;
    }
    slot->len = (uint8_t)len;
    slot->cls = (uint8_t)cls;
    slot->used = true;
    slot->order = o->state.next_order++;
    return true;
}

bool rw_outbox_push(rw_outbox *o, rw_outbox_class cls, const uint8_t *frame, size_t len)
{
    if (len == 0u || len > RW_MAX_FRAME_LEN) {
        ++o->state.dropped;
        return false;
    }
    rw_outbox_slot *slot = rw_outbox_reserve(o, cls);
    if (slot == NULL) {
        return false;
    }
    memcpy(slot->bytes, frame, len);
    return rw_outbox_commit(o, slot, cls, len);
}

const rw_outbox_slot *rw_outbox_peek(const rw_outbox *o)
{
    const rw_outbox_slot *best = NULL;
    if (o->state.used == 0u) {
        return NULL;
    }
    unsigned seen = 0u;
    for (unsigned i = 0u; i < RW_OUTBOX_SLOTS && seen < o->state.used; ++i) { /* stops after the last used slot */
        const rw_outbox_slot *s = &o->state.slots[i];
        if (!s->used) {
            continue;
        }
        ++seen;
        if (best == NULL || s->cls < best->cls || (s->cls == best->cls && s->order < best->order)) {
            best = s;
        }
    }
    return best;
}

void rw_outbox_pop(rw_outbox *o, const rw_outbox_slot *slot)
{
    /* the slot's index from its address (no scan: this runs in the tick that begins a frame's signing) */
    const uintptr_t offset = (uintptr_t)slot - (uintptr_t)o->state.slots;
    if (offset >= sizeof o->state.slots || offset % sizeof o->state.slots[0] != 0u) {
        return; /* not one of this outbox's slots */
    }
    rw_outbox_slot *s = &o->state.slots[offset / sizeof o->state.slots[0]];
    if (s->used) {
        s->used = false;
        --o->state.used;
    }
}

uint16_t rw_outbox_dropped(const rw_outbox *o)
{
    return o->state.dropped;
}

void rw_outbox_count_drop(rw_outbox *o)
{
    ++o->state.dropped;
}
