/* Recently executed commands, so that a retransmission (same seq, same checksum) is answered again with
 * the same verdict but never executed twice. A small ring: the host retries within a second or two. */
#ifndef RW_DUPLICATE_CACHE_H
#define RW_DUPLICATE_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#define RW_DUPLICATE_CACHE_SIZE 32u
#define RW_DUPLICATE_WINDOW_MS 5000u

typedef struct rw_duplicate_entry {
    uint8_t msg_id;
    uint16_t seq;
    uint16_t checksum;  /* the frame's checksum: same seq with other content is a new command */
    uint8_t nack_reason; /* 0 = it was ACKed */
    int32_t nack_detail;
    uint32_t time_ms;
    bool used;
} rw_duplicate_entry;

typedef struct rw_duplicate_cache {
    struct {
        rw_duplicate_entry entries[RW_DUPLICATE_CACHE_SIZE];
        uint8_t next;
    } state;
} rw_duplicate_cache;

void rw_duplicate_cache_reset(rw_duplicate_cache *c);
/* The cached entry for this command if it was seen within the window, else NULL. */
const rw_duplicate_entry *rw_duplicate_cache_find(const rw_duplicate_cache *c, uint8_t msg_id, uint16_t seq,
                                                  uint16_t checksum, uint32_t now_ms);
void rw_duplicate_cache_store(rw_duplicate_cache *c, uint8_t msg_id, uint16_t seq, uint16_t checksum,
                              uint8_t nack_reason, int32_t nack_detail, uint32_t now_ms);

#endif /* RW_DUPLICATE_CACHE_H */
