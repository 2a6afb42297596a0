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

/* Position register -> degrees in [0, 300]. */
float rw_ax12_position_deg(uint16_t raw);
/* Present speed register -> signed degrees per second (+ = counter-clockwise). */
float rw_ax12_speed_deg_s(uint16_t raw);
/* Present load register -> signed per mille of max torque (+ = pushing counter-clockwise). */
int16_t rw_ax12_load_permille(uint16_t raw);
/* Signed speed (deg/s, + = counter-clockwise) -> wheel-mode moving speed register; saturates at 1023. */
uint16_t rw_ax12_moving_speed_raw(float speed_deg_s);

#endif /* RW_AX12_H */
