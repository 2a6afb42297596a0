/* SIL lockstep with the plant: the plant owns the clock. Each SIL_SENSORS datagram from the plant is one
 * control tick; the SIL answers with SIL_ACTUATORS. The sensor HAL interfaces (encoder, battery) return
 * the last sensor values; the ESC output stores the pulse for the answer (the spindle goes through
 * sil_spindle_bus.h, the board's split transaction). Relays only: no physics here. */
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
    uint16_t esc_pulse_us;      /* the pulse the ESCs have (applied at the start of the tick, as on the board) */
    uint16_t esc_pulse_third_us; /* the same, thirds of a microsecond (the timer's resolution) */
    uint16_t esc_staged_third_us; /* the core's latest pulse (thirds of a us), applied at the start of the next tick */
    uint16_t spindle_moving_speed_raw; /* latest output (the spindle bus's last write, sil_spindle_bus.h) */
    uint32_t bad_datagrams;
    uint16_t tx_seq;
} sil_lockstep;

bool sil_lockstep_open(sil_lockstep *ls, uint16_t port);
void sil_lockstep_close(sil_lockstep *ls);
/* Wait up to timeout_ms for the next SIL_SENSORS; 1 = got one, 0 = timeout, -1 = interrupted/error. */
int sil_lockstep_wait_sensors(sil_lockstep *ls, int timeout_ms);
/* Start of a tick: the pulse the core wrote in the previous tick reaches the ESCs (the board's TC3 interrupt
 * applies the staged pulse first thing, so the update has a fixed phase: arduino_esc_output.h). */
void sil_lockstep_apply_esc(sil_lockstep *ls);
/* Answer the current tick with the stored outputs. */
void sil_lockstep_send_actuators(sil_lockstep *ls);

rw_hal_encoder sil_lockstep_encoder(sil_lockstep *ls);
rw_hal_battery sil_lockstep_battery(sil_lockstep *ls);
rw_hal_esc_output sil_lockstep_esc(sil_lockstep *ls);

#endif /* SIL_LOCKSTEP_H */
