/* Spindle servo on the board: one AX-12A (Dynamixel Protocol 1.0, 1 Mbps) through the DYNAMIXEL Shield for
 * MKR (half-duplex TTL on Serial1, direction pin A6), driven with the Dynamixel2Arduino library in wheel
 * mode with raw register values. Implements rw_hal_spindle (hal/rw_hal_spindle.h); the core calls it every
 * RW_CORE_SPINDLE_PERIOD_MS (10 ms): one read of registers 36-41 and one write of register 32 each time.
 *
 * Optional home limit switch on D5 (normally open, to GND, internal pull-up): closed = LOW = limit_switch.
 * Without a switch the pin reads open and the core homes on the stall (load) condition. */
#ifndef RW_ARDUINO_SPINDLE_H
#define RW_ARDUINO_SPINDLE_H

#include <stdint.h>

extern "C" {
#include "rw_hal_spindle.h"
}

static const uint8_t RW_SPINDLE_DXL_ID = 1u;            /* AX-12A factory ID */
static const uint32_t RW_SPINDLE_DXL_BAUD = 1000000u;   /* AX-12A factory baud rate (register 4 = 1) */
/* Status packet wait while running: the library counts whole millis() ticks, so 2 means 1-2 ms; an answer
 * takes about 0.2 ms after the instruction, so it never times out a servo that answers. */
static const uint32_t RW_SPINDLE_TIMEOUT_MS = 2u;
/* Status packet wait during setup (boot, or the servo back after a silence). */
static const uint32_t RW_SPINDLE_SETUP_TIMEOUT_MS = 10u;
/* After an unanswered read the bus is left alone this long (reads report "no answer" at once), so an
 * absent or unpowered servo costs one 1-2 ms wait per retry instead of one per spindle step. */
static const uint32_t RW_SPINDLE_RETRY_MS = 500u;

/* AX-12A control table addresses used here (Protocol 1.0). */
enum rw_ax12_register {
    RW_AX12_REG_RETURN_DELAY = 5u,     /* EEPROM, 1 byte, 2 us a unit */
    RW_AX12_REG_CW_ANGLE_LIMIT = 6u,   /* EEPROM, 2 bytes; with CCW also 0: wheel mode */
    RW_AX12_REG_CCW_ANGLE_LIMIT = 8u,  /* EEPROM, 2 bytes */
    RW_AX12_REG_TORQUE_ENABLE = 24u,   /* RAM, 1 byte */
    RW_AX12_REG_MOVING_SPEED = 32u,    /* RAM, 2 bytes: wheel mode 0-1023 CCW, +1024 CW */
    RW_AX12_REG_PRESENT_POSITION = 36u /* RAM, 6 bytes read as one: position, speed, load (2 bytes each) */
};

struct rw_arduino_spindle {
    bool configured;          /* wheel mode set up and torque on since the servo last answered */
    bool silent;              /* the last read went unanswered: retry after RW_SPINDLE_RETRY_MS */
    uint32_t silent_since_ms;
    uint32_t last_setup_ms;   /* a failed setup is retried at most every RW_SPINDLE_RETRY_MS */
    uint32_t reads;           /* answered reads */
    uint32_t read_failures;   /* unanswered reads (bus attempts only) */
    uint32_t write_failures;  /* writes without a valid status packet */
    uint32_t setups;          /* wheel-mode setups done (boot, and after each silence) */
    uint32_t eeprom_writes;   /* EEPROM registers rewritten by a setup (0 once the servo is configured) */
};

/* Serial1 at 1 Mbps, Protocol 1.0, limit switch pin; then the wheel-mode setup (torque off, return delay
 * 0 and angle limits 0 written only if they differ - EEPROM -, moving speed 0, torque on). Returns whether
 * the servo answered; if not, the setup runs again when it first answers a read. */
bool rw_arduino_spindle_begin(rw_arduino_spindle *sp);

rw_hal_spindle rw_arduino_spindle_hal(rw_arduino_spindle *sp);

#endif /* RW_ARDUINO_SPINDLE_H */
