/* SIL stand-in for the board's flash: the configuration record in a file (written atomically: temp + rename).
 *
 * As on the board, a PROVISION_COMMIT's write (request_save) does not happen in the tick: the record is
 * copied, and sil_config_store_service (the background loop's place, between two ticks) writes it
 * save_ticks ticks after the request. The default is 1 (answered on the next tick): the board's ~25 ms is not
 * modelled, because the factory jig provisions every SIL session with the plant clock standing still and 25
 * extra ticks there shift the schedule's phase of every run after it. */
#ifndef SIL_CONFIG_STORE_H
#define SIL_CONFIG_STORE_H

#include <stdint.h>

#include "rw_config.h"
#include "rw_hal_config_store.h"

/* Ticks a requested write takes (the board: two row erases + five page writes, up to ~25 ms; see above). */
#define SIL_CONFIG_STORE_DEFAULT_SAVE_TICKS 1u

typedef struct sil_config_store {
    char path[512];
    uint32_t save_ticks;       /* ticks from a request to its write */
    uint32_t countdown;        /* ticks left for the write in progress */
    uint8_t status;            /* rw_config_save_status of the last request */
    rw_config pending;         /* the requested record */
    uint32_t requests;         /* counters (printed by rw_sil on exit) */
    uint32_t refused_busy;
    uint32_t writes_ok;
    uint32_t writes_failed;
} sil_config_store;

rw_hal_config_store sil_config_store_hal(sil_config_store *s);
/* Between two ticks: a requested write whose time has come is written (status DONE or FAILED). */
void sil_config_store_service(sil_config_store *s);

#endif /* SIL_CONFIG_STORE_H */
