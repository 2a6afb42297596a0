/* SIL lockstep with the plant: the plant owns the clock. Each SIL_SENSORS datagram from the plant is one
 * control tick; the SIL answers with SIL_ACTUATORS. The sensor HAL interfaces (encoder, battery) return
 * the last sensor values; the ESC output stores the pulse for the answer. Relays only: no physics here. */
#ifndef SIL_LOCKSTEP_H
#define SIL_LOCKSTEP_H

#include <netinet/in.h>
#include <stdbool.h>
#include <stdint.h>

#include "rw_hal.h"
#include "rw_protocol.h"

typedef struct sil_lockstep {
    int fd;
    uint16_t port;
    struct sockaddr_in plant;
    bool has_plant;
    rw_msg_sil_sensors sensors; /* latest */
    uint16_t esc_pulse_us;      /* latest output */
    uint16_t esc_pulse_third_us; /* the same, thirds of a microsecond (the timer's resolution) */
    uint16_t spindle_moving_speed_raw; /* latest output */
    uint32_t bad_datagrams;
    uint16_t tx_seq;
} sil_lockstep;

bool sil_lockstep_open(sil_lockstep *ls, uint16_t port);
void sil_lockstep_close(sil_lockstep *ls);
/* Wait up to timeout_ms for the next SIL_SENSORS; 1 = got one, 0 = timeout, -1 = interrupted/error. */
int sil_lockstep_wait_sensors(sil_lockstep *ls, int timeout_ms);
/* Answer the current tick with the stored outputs. */
void sil_lockstep_send_actuators(sil_lockstep *ls);

rw_hal_encoder sil_lockstep_encoder(sil_lockstep *ls);
rw_hal_battery sil_lockstep_battery(sil_lockstep *ls);
rw_hal_esc_output sil_lockstep_esc(sil_lockstep *ls);
rw_hal_spindle sil_lockstep_spindle(sil_lockstep *ls);

#endif /* SIL_LOCKSTEP_H */
