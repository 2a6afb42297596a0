#include "sil_spindle_bus.h"

#include <string.h>

void sil_spindle_bus_init(sil_spindle_bus *bus, uint32_t transaction_us, uint32_t tick_us)
{
    memset(bus, 0, sizeof *bus);
    rw_spindle_exchange_init(&bus->exchange);
    bus->transaction_us = transaction_us > 0u ? transaction_us : 1u;
    bus->tick_us = tick_us;
}

void sil_spindle_bus_service(sil_spindle_bus *bus, const rw_msg_sil_sensors *sensors)
{
    uint32_t budget_us = bus->tick_us;
    if (bus->carry_us >= budget_us) {
        bus->carry_us -= budget_us; /* the transaction begun earlier is still on the bus */
        return;
    }
    budget_us -= bus->carry_us;
    bus->carry_us = 0u;
    for (;;) {
        const rw_spindle_job job = rw_spindle_exchange_next_job(&bus->exchange);
        if (job.kind == RW_SPINDLE_JOB_NONE) {
            return;
        }
        if (bus->transaction_us > budget_us) {
            bus->carry_us = bus->transaction_us - budget_us; /* done in a later step, with that step's values */
            return;
        }
        budget_us -= bus->transaction_us;
        const bool answered = sensors->spindle_answered != 0u;
        if (job.kind == RW_SPINDLE_JOB_WRITE) {
            bus->moving_speed_raw = job.moving_speed_raw; /* the servo executes it, answered or not */
            rw_spindle_exchange_write_done(&bus->exchange, &job, answered);
        } else {
            rw_spindle_reading reading = {
                .position_raw = sensors->spindle_position_raw,
                .speed_raw = sensors->spindle_speed_raw,
                .load_raw = sensors->spindle_load_raw,
                .limit_switch = sensors->limit_switch != 0u,
            };
            rw_spindle_exchange_read_done(&bus->exchange, &job, answered ? &reading : NULL);
        }
    }
}

rw_hal_spindle sil_spindle_bus_hal(sil_spindle_bus *bus)
{
    return rw_spindle_exchange_hal(&bus->exchange);
}
