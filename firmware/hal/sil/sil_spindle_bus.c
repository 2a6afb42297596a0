#include "sil_spindle_bus.h"

#include <string.h>

void sil_spindle_bus_init(sil_spindle_bus *bus, uint32_t transaction_us, uint32_t tick_us)
{
    memset(bus, 0, sizeof *bus);
    rw_spindle_exchange_init(&bus->exchange);
    bus->transaction_us = transaction_us > 0u ? transaction_us : 1u;
    bus->tick_us = tick_us;
}

/* Complete a job with the plant's current values. */
static void finish(sil_spindle_bus *bus, const rw_spindle_job *job, const rw_msg_sil_sensors *sensors)
{
    const bool answered = sensors->spindle_answered != 0u;
    if (job->kind == RW_SPINDLE_JOB_WRITE) {
        bus->moving_speed_raw = job->moving_speed_raw; /* the servo executes it, answered or not */
        rw_spindle_exchange_write_done(&bus->exchange, job, answered);
        return;
    }
    rw_spindle_reading reading = {
        .position_raw = sensors->spindle_position_raw,
        .speed_raw = sensors->spindle_speed_raw,
        .load_raw = sensors->spindle_load_raw,
        .limit_switch = sensors->limit_switch != 0u,
    };
    rw_spindle_exchange_read_done(&bus->exchange, job, answered ? &reading : NULL);
}

void sil_spindle_bus_service(sil_spindle_bus *bus, const rw_msg_sil_sensors *sensors)
{
    uint32_t budget_us = bus->tick_us;
    for (;;) {
        if (bus->in_flight.kind == RW_SPINDLE_JOB_NONE) {
            bus->in_flight = rw_spindle_exchange_next_job(&bus->exchange);
            bus->remaining_us = bus->transaction_us;
            if (bus->in_flight.kind == RW_SPINDLE_JOB_NONE) {
                return;
            }
        }
        if (bus->remaining_us > budget_us) {
            bus->remaining_us -= budget_us; /* still on the bus at the next tick */
            return;
        }
        budget_us -= bus->remaining_us;
        finish(bus, &bus->in_flight, sensors);
        bus->in_flight.kind = RW_SPINDLE_JOB_NONE;
    }
}

rw_hal_spindle sil_spindle_bus_hal(sil_spindle_bus *bus)
{
    return rw_spindle_exchange_hal(&bus->exchange);
}
