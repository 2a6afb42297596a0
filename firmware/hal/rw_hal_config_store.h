/* Non-volatile storage of the device configuration (rw_config): flash on the board (FlashStorage), a file
 * in SIL. The core owns the record's layout and checks it (version, size, CRC); the store moves bytes.
 *
 * Two ways to write:
 *  - save: at once, in the caller. Only the first tick's boot-counter write uses it; on the board that tick
 *    runs in setup(), before the tick interrupt starts.
 *  - request_save + save_status: a PROVISION_COMMIT's write, from the control tick. A flash row erase and its
 *    page writes stall the CPU for up to ~25 ms on the SAMD21, so the tick only hands the record over (a copy)
 *    and the store's background side writes it (the board's loop(), while the rope is down; the SIL between
 *    ticks); the core polls save_status each tick and answers the command when the write is done. */
#ifndef RW_HAL_CONFIG_STORE_H
#define RW_HAL_CONFIG_STORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* save_status values. */
typedef enum {
    RW_CONFIG_SAVE_IDLE = 0,   /* nothing requested yet */
    RW_CONFIG_SAVE_BUSY = 1,   /* requested, not written yet */
    RW_CONFIG_SAVE_DONE = 2,   /* the last request was written (and read back) */
    RW_CONFIG_SAVE_FAILED = 3, /* the last request could not be written */
} rw_config_save_status;

typedef struct rw_hal_config_store {
    void *ctx;
    /* Read len bytes of the stored record into buf; false if nothing is stored (buf unspecified). */
    bool (*load)(void *ctx, void *buf, size_t len);
    /* Write the record now; false on failure. */
    bool (*save)(void *ctx, const void *buf, size_t len);
    /* Copy the record for a write outside the tick; false (nothing started) while a write is BUSY or for a
     * length the store cannot hold. Bounded: a copy of len bytes. */
    bool (*request_save)(void *ctx, const void *buf, size_t len);
    /* The last request's rw_config_save_status (kept until the next request). */
    uint8_t (*save_status)(void *ctx);
} rw_hal_config_store;

#endif /* RW_HAL_CONFIG_STORE_H */
