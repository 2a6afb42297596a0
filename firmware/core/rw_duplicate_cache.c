#include "rw_duplicate_cache.h"

void rw_duplicate_cache_reset(rw_duplicate_cache *c)
{
    for (unsigned i = 0u; i < RW_DUPLICATE_CACHE_SIZE; ++i) {
        c->state.entries[i].used = false;
    }
    c->state.next = 0u;
}

const rw_duplicate_entry *rw_duplicate_cache_find(const rw_duplicate_cache *c, uint8_t msg_id, uint16_t seq,
                                                  uint16_t checksum, uint32_t now_ms)
{
    for (unsigned i = 0u; i < RW_DUPLICATE_CACHE_SIZE; ++i) {
        const rw_duplicate_entry *e = &c->state.entries[i];
        if (e->used && e->msg_id == msg_id && e->seq == seq && e->checksum == checksum &&
            (uint32_t)(now_ms - e->time_ms) <= RW_DUPLICATE_WINDOW_MS) {
            return e;
        }
    }
    return 0;
}

void rw_duplicate_cache_store(rw_duplicate_cache *c, uint8_t msg_id, uint16_t seq, uint16_t checksum,
                              uint8_t nack_reason, int32_t nack_detail, uint32_t now_ms)
{
    rw_duplicate_entry *e = &c->state.entries[c->state.next];
    e->msg_id = msg_id;
    e->seq = seq;
    e->checksum = checksum;
    e->nack_reason = nack_reason;
    e->nack_detail = nack_detail;
    e->time_ms = now_ms;
    e->used = true;
    c->state.next = (uint8_t)((c->state.next + 1u) % RW_DUPLICATE_CACHE_SIZE);
}
