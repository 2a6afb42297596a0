/* AX-12A register units (Dynamixel Protocol 1.0, wheel mode), converted in this one place.
 *
 * Position: 0-1023 over 0-300 degrees; 300-360 degrees is a dead zone where the register means nothing.
 * Speed and load: 10-bit magnitude, bit 10 = clockwise. Present speed: about 0.111 rpm a unit. Wheel-mode
 * moving speed: about 0.1 % of full output a unit (open-loop drive: 1023 is the no-load speed, 59 rpm at
 * 12 V, less under load or at a lower supply, so the position loop closes on the measured angle); written raw (Dynamixel2Arduino's percent unit maps
 * -100..100 % onto raw 0..2047 for AX servos, so its "0 %" spins near full speed one way).
 * Convention: counter-clockwise (bit 10 clear) = positive = the guide retracts (more rope inside). */
#ifndef RW_AX12_H
#define RW_AX12_H

#include <stdint.h>

#define RW_AX12_DEG_PER_POSITION_UNIT (300.0f / 1023.0f)
#define RW_AX12_VALID_RANGE_DEG 300.0f
#define RW_AX12_RPM_PER_SPEED_UNIT 0.111f
#define RW_AX12_WHEEL_NO_LOAD_RPM 59.0f
#define RW_AX12_DIRECTION_BIT 0x0400u
#define RW_AX12_MAGNITUDE_MASK 0x03FFu

/* The multi-turn angle unit of the firmware (rw_multiturn, rw_spindle): 1/2560 of a position register unit,
 * so that a turn is a whole number of ticks (360 deg = 1227.6 register units = 3,142,656 ticks; one tick is
 * 0.000115 deg) and a register value converts by a multiplication. int32 ticks span +-683 turns. */
#define RW_AX12_TICKS_PER_POSITION_UNIT 2560
#define RW_AX12_TICKS_PER_TURN 3142656
#define RW_AX12_TICKS_VALID_RANGE (1023 * RW_AX12_TICKS_PER_POSITION_UNIT) /* 300 degrees */
#define RW_AX12_TICKS_PER_DEG 8729.6f /* 2560 x 1023 / 300, exact */
/* One present-speed unit (0.111 rpm = 0.666 deg/s = 5.8139 ticks/ms) in ticks per millisecond, Q10
 * (5953.4 rounded: 0.007 % slow, 0.004 degrees over the 60 degree dead zone). */
#define RW_AX12_SPEED_UNIT_TICKS_PER_MS_Q10 5953
/* Wheel-mode moving speed register units per (deg/s): 1023 at the no-load speed. */
#define RW_AX12_MOVING_UNITS_PER_DEG_S (1023.0f / (RW_AX12_WHEEL_NO_LOAD_RPM * 6.0f))

/* Position register -> degrees in [0, 300]. */
float rw_ax12_position_deg(uint16_t raw);
/* Present speed register -> signed degrees per second (+ = counter-clockwise). */
float rw_ax12_speed_deg_s(uint16_t raw);
/* Present load register -> signed per mille of max torque (+ = pushing counter-clockwise). */
int16_t rw_ax12_load_permille(uint16_t raw);
/* Signed speed (deg/s, + = counter-clockwise) -> wheel-mode moving speed register; saturates at 1023. */
uint16_t rw_ax12_moving_speed_raw(float speed_deg_s);
/* Position register -> multi-turn ticks in [0, RW_AX12_TICKS_VALID_RANGE] (saturates at 1023 as above). */
int32_t rw_ax12_position_ticks(uint16_t raw);
/* Present speed register -> signed ticks per millisecond, Q10 (+ = counter-clockwise). */
int32_t rw_ax12_speed_ticks_per_ms_q10(uint16_t raw);

#endif /* RW_AX12_H */
