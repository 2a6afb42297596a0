/* Battery voltage (ADC behind a divider on the board; the plant's battery model in SIL). */
#ifndef RW_HAL_BATTERY_H
#define RW_HAL_BATTERY_H

#include <stdint.h>

typedef struct rw_hal_battery {
    void *ctx;
    uint16_t (*read_mv)(void *ctx); /* battery terminal voltage, millivolts */
} rw_hal_battery;

#endif /* RW_HAL_BATTERY_H */
