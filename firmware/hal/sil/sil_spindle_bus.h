/* The spindle bus in SIL: the same split transaction as on the board (core/rw_spindle_exchange.h). The core's
 * spindle calls inside the tick only post a write and take the reading of the previous request; after each
 * tick, the SIL's background step (sil_spindle_bus_service) serves the posted jobs as the board's background
 * loop does between ticks: each transaction takes transaction_us of bus time, as many as fit in one tick
 * period (a transaction longer than what is left runs on into the next ticks and completes with the values of
 * the tick it ends in; a slow bus makes the core step without a fresh reading: counted late / missing).
 * The write reaches the plant in this tick's SIL_ACTUATORS; the read answers with this tick's SIL_SENSORS,
 * or with no reply when the plant says the servo did not answer (a silent servo, or a reply lost on the bus:
 * plant_faults.SpindleReplyLoss). Relays only: no physics here. */
#ifndef SIL_SPINDLE_BUS_H
#define SIL_SPINDLE_BUS_H

#include <stdint.h>

#include "rw_hal.h"
#include "rw_protocol.h"
#include "rw_spindle_exchange.h"

/* A read or write transaction on the AX-12A's 1 Mbps bus with the library's polling (arduino_spindle.cpp). */
#define SIL_SPINDLE_BUS_DEFAULT_TRANSACTION_US 350u

typedef struct sil_spindle_bus {
    rw_spindle_exchange exchange;
    uint32_t transaction_us; /* bus time of one transaction */
    uint32_t tick_us;        /* time the background step has between two ticks */
    rw_spindle_job in_flight; /* the transaction on the bus (kind NONE: the bus is idle) */
    uint32_t remaining_us;   /* its bus time still to run */
    uint16_t moving_speed_raw; /* the last value written to the servo (what the plant gets) */
} sil_spindle_bus;

void sil_spindle_bus_init(sil_spindle_bus *bus, uint32_t transaction_us, uint32_t tick_us);
/* The background step after a tick: serve jobs with the plant's current sensor values. */
void sil_spindle_bus_service(sil_spindle_bus *bus, const rw_msg_sil_sensors *sensors);
/* The tick's side (the core's rw_hal_spindle). */
rw_hal_spindle sil_spindle_bus_hal(sil_spindle_bus *bus);

#endif /* SIL_SPINDLE_BUS_H */
