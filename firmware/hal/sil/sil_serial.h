/* SIL stand-in for the board's USB serial: a pseudo-terminal. The host opens its slave side (the path
 * printed at start) with pyserial, exactly as it opens /dev/ttyACM0 of a board; frames are COBS-encoded
 * with a 0x00 delimiter. Implements rw_hal_link (trusted link: provisioning). */
#ifndef SIL_SERIAL_H
#define SIL_SERIAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_cobs.h"
#include "rw_cobs_deframer.h"
#include "rw_hal_link.h"
#include "rw_protocol.h"

typedef struct sil_serial {
    int fd;                 /* pty master */
    char path[128];         /* slave side */
    rw_cobs_deframer rx;    /* received bytes -> frames (the board's serial HAL uses the same) */
} sil_serial;

bool sil_serial_open(sil_serial *s);
void sil_serial_close(sil_serial *s);
rw_hal_link sil_serial_hal(sil_serial *s);

#endif /* SIL_SERIAL_H */
