/* Non-volatile storage of the device configuration (rw_config): flash on the board (FlashStorage), a file
 * in SIL. The core owns the record's layout and checks it (version, size, CRC); the store moves bytes. */
#ifndef RW_HAL_CONFIG_STORE_H
#define RW_HAL_CONFIG_STORE_H

#include <stdbool.h>
#include <stddef.h>

typedef struct rw_hal_config_store {
    void *ctx;
    /* Read len bytes of the stored record into buf; false if nothing is stored (buf unspecified). */
    bool (*load)(void *ctx, void *buf, size_t len);
    /* Write the record; false on failure. */
    bool (*save)(void *ctx, const void *buf, size_t len);
} rw_hal_config_store;

#endif /* RW_HAL_CONFIG_STORE_H */
