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
    uint32_t notes;         /* status lines written */
    uint32_t notes_dropped; /* status lines dropped: nobody listening */
} sil_serial;

bool sil_serial_open(sil_serial *s);
void sil_serial_close(sil_serial *s);
/* Whether a host has the port open (the pseudo-terminal's other side), as the board checks DTR. */
bool sil_serial_listening(const sil_serial *s);
/* A line of text for a person at a terminal between the frames, as the board's rw_arduino_serial_link_note:
 * "rw: text\n" and a 0x00 delimiter (a host's COBS reader drops it as one malformed frame); dropped (counted)
 * while nobody listens. */
void sil_serial_note(sil_serial *s, const char *text);
rw_hal_link sil_serial_hal(sil_serial *s);

#endif /* SIL_SERIAL_H */
