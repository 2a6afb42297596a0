/* SIL stand-in for the board's USB serial: a pseudo-terminal. The host opens its slave side (the path
 * printed at start) with pyserial, exactly as it opens /dev/ttyACM0 of a board; frames are COBS-encoded
 * with a 0x00 delimiter. Implements rw_hal_link (trusted link: provisioning). */
#ifndef SIL_SERIAL_H
#define SIL_SERIAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_cobs.h"
#include "rw_hal_link.h"
#include "rw_protocol.h"

#define SIL_SERIAL_RX_MAX 512u

typedef struct sil_serial {
    int fd;                 /* pty master */
    char path[128];         /* slave side */
    uint8_t rx[SIL_SERIAL_RX_MAX];
    size_t rx_len;
    bool rx_overflow;       /* current frame too long: dropped up to the next delimiter */
    uint32_t frames_in;
    uint32_t bad_frames;
} sil_serial;

bool sil_serial_open(sil_serial *s);
void sil_serial_close(sil_serial *s);
rw_hal_link sil_serial_hal(sil_serial *s);

#endif /* SIL_SERIAL_H */
