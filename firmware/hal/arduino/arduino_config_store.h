/* Configuration store on the board: the core's rw_config record (key, WiFi credentials, parameters, boot
 * counter; core/rw_config.h) kept in flash with FlashStorage (cmaglie/FlashStorage). Implements
 * rw_hal_config_store (hal/rw_hal_config_store.h): it moves bytes, the core owns and checks the layout.
 *
 * The record lives in a 256-byte-aligned array in the program image (FlashStorage's model), one or more
 * whole flash rows of its own. Consequences (docs/board.md): every firmware upload erases it (the board
 * boots unprovisioned, boot counter from 1); each save erases and rewrites the rows (a few ms with the CPU
 * stalled on flash), and a row endures about 25,000 erase cycles - the core saves at every boot (boot
 * counter) and at each PROVISION_COMMIT. */
#ifndef RW_ARDUINO_CONFIG_STORE_H
#define RW_ARDUINO_CONFIG_STORE_H

#include <stdint.h>

extern "C" {
#include "rw_config.h"
#include "rw_hal_config_store.h"
}

/* Flash reserved for the record: sizeof(rw_config) rounded up to whole 256-byte rows. */
static const uint32_t RW_CONFIG_AREA_BYTES = (sizeof(rw_config) + 255u) / 256u * 256u;

struct rw_arduino_config_store {
    uint32_t loads;         /* load calls that found a written record */
    uint32_t saves;         /* records written and verified */
    uint32_t save_failures; /* refused length, or the read-back differed from the record */
    /* a PROVISION_COMMIT's write: requested by the tick (copy + status), done by the background loop */
    rw_config pending;            /* the record to write (the tick copies it in while status is not BUSY) */
    volatile uint8_t status;      /* rw_config_save_status: BUSY from the request until the loop wrote it */
    uint32_t requests;            /* request_save calls taken */
    uint32_t refused_busy;        /* request_save calls refused (a write BUSY, or a bad length) */
    uint32_t deferred_passes;     /* background passes a BUSY write waited because the rope was up */
    uint32_t max_save_us;         /* longest background write (erase + write + read-back), micros() */
};

/* load: len bytes of the area; false when len exceeds the area or the area is blank (all 0x00 as the
 * upload leaves it, or all 0xFF as an erase leaves it). save: erase the rows, write, read back and
 * compare; false on a length that is over the area or not a multiple of 4, or on a mismatch (the boot-counter
 * write of the core's first tick, in setup(), before the tick interrupt runs). request_save (from the tick):
 * copies the record and marks it BUSY; false while BUSY or for a length other than sizeof(rw_config). */
rw_hal_config_store rw_arduino_config_store_hal(rw_arduino_config_store *store);

/* Background loop, every pass: a BUSY write is done here (save: erase, write, read back; the CPU stalls on the
 * flash meanwhile, up to ~25 ms, the ESC PWM runs on in hardware), only while rope_down; else it waits,
 * counted. One write per pass at most. */
void rw_arduino_config_store_service(rw_arduino_config_store *store, bool rope_down);

#endif /* RW_ARDUINO_CONFIG_STORE_H */
