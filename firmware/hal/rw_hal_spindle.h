/* Spindle servo bus: the AX-12A (Dynamixel Protocol 1.0) that turns the lead screw, in wheel mode.
 * Raw register values cross this interface; the core converts them (rw_ax12.h). On the board the read
 * is one transaction of present position, speed and load (registers 36-41); in SIL the plant answers. */
#ifndef RW_HAL_SPINDLE_H
#define RW_HAL_SPINDLE_H

#include <stdbool.h>
#include <stdint.h>

typedef struct rw_spindle_reading {
    uint16_t position_raw; /* present position, 0-1023 over 300 degrees (meaningless in the dead zone) */
    uint16_t speed_raw;    /* present speed, 0-1023, bit 10 = clockwise */
    uint16_t load_raw;     /* present load, 0-1023 in 0.1 % of max torque, bit 10 = clockwise */
    bool limit_switch;     /* home limit switch closed (false where none is fitted) */
} rw_spindle_reading;

typedef struct rw_hal_spindle {
    void *ctx;
    /* Read position, speed and load; false if the servo did not answer (out left unchanged). */
    bool (*read)(void *ctx, rw_spindle_reading *out);
    /* Write the wheel-mode moving speed register: 0-1023 counter-clockwise, +1024 for clockwise. */
    void (*write_moving_speed_raw)(void *ctx, uint16_t raw);
} rw_hal_spindle;

#endif /* RW_HAL_SPINDLE_H */
