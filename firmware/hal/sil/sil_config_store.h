/* SIL stand-in for the board's flash: the configuration record in a file (written atomically: temp + rename). */
#ifndef SIL_CONFIG_STORE_H
#define SIL_CONFIG_STORE_H

#include "rw_hal_config_store.h"

typedef struct sil_config_store {
    char path[512];
} sil_config_store;

rw_hal_config_store sil_config_store_hal(sil_config_store *s);

#endif /* SIL_CONFIG_STORE_H */
