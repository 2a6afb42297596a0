/* Motor battery voltage on the board: ADC on A1 behind a resistor divider, converted to millivolts.
 * Implements rw_hal_battery (hal/rw_hal_battery.h). */
#ifndef RW_ARDUINO_BATTERY_H
#define RW_ARDUINO_BATTERY_H

#include <stdint.h>

extern "C" {
#include "rw_hal_battery.h"
}

/* Battery voltage that gives the ADC's full scale (3.3 V at the pin) for the assumed divider
 * 47 kOhm (battery side) over 10 kOhm (ground side): 3.3 V x 57 / 10 = 18.81 V, millivolts. A 4S pack
 * (16.8 V full) then reads 2.95 V at the pin. A board setting, not in the configuration record: calibrate
 * by changing this constant (docs/board.md). */
static const uint16_t RW_BATTERY_DEFAULT_FULL_SCALE_MV = 18810u;

struct rw_arduino_battery {
    uint16_t full_scale_mv; /* battery millivolts at ADC code 4096 (divider and reference together) */
    uint16_t last_mv;       /* latest conversion, millivolts */
};

/* Configure the ADC (12 bit, reference VDDANA/2 with gain 1/2 = 3.3 V full scale) on the battery pin and
 * take one blocking first reading (about 30 us). */
void rw_arduino_battery_begin(rw_arduino_battery *bat, uint16_t full_scale_mv);

/* Battery millivolts from the latest finished conversion; starts the next one (never waits). */
uint16_t rw_arduino_battery_read_mv(rw_arduino_battery *bat);

rw_hal_battery rw_arduino_battery_hal(rw_arduino_battery *bat);

#endif /* RW_ARDUINO_BATTERY_H */
