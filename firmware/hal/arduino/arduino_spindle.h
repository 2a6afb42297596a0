/* Spindle servo on the board: one AX-12A (Dynamixel Protocol 1.0, 1 Mbps) through the DYNAMIXEL Shield for
 * MKR (half-duplex TTL on Serial1, direction pin A6), driven with the Dynamixel2Arduino library in wheel
 * mode with raw register values.
 *
 * Split transaction (core/rw_spindle_exchange.h): the core's rw_hal_spindle calls, inside the control tick,
 * only hand requests and results over in RAM; the bus transactions run in the background loop
 * (rw_arduino_spindle_service), one per call, each bounded by its status timeout. The core calls read and
 * write every RW_CORE_SPINDLE_PERIOD_MS (10 ms), so the loop does one read of registers 36-41 and one write
 * of register 32 per 10 ms, and the core steps with the reading of the previous period.
 *
 * Optional home limit switch on D5 (normally open, to GND, internal pull-up): closed = LOW = limit_switch,
 * sampled when the read's reply arrives. Without a switch the pin reads open and the core homes on the stall
 * (load) condition. */
#ifndef RW_ARDUINO_SPINDLE_H
#define RW_ARDUINO_SPINDLE_H

#include <stdint.h>

extern "C" {
#include "rw_hal_spindle.h"
#include "rw_spindle_exchange.h"
}

static const uint8_t RW_SPINDLE_DXL_ID = 1u;            /* AX-12A factory ID */
static const uint32_t RW_SPINDLE_DXL_BAUD = 1000000u;   /* AX-12A factory baud rate (register 4 = 1) */
/* Status packet wait while running: the library counts whole millis() ticks, so 2 means 1-2 ms; an answer
 * takes about 0.2 ms after the instruction, so it never times out a servo that answers. */
static const uint32_t RW_SPINDLE_TIMEOUT_MS = 2u;
/* Status packet wait of a wheel-mode setup step (boot, or the servo back after a silence). */
static const uint32_t RW_SPINDLE_SETUP_TIMEOUT_MS = 10u;
/* This many unanswered reads in a row make the servo silent (one lost reply is only a step without a reading). */
static const uint8_t RW_SPINDLE_SILENT_AFTER_FAILURES = 3u;
/* After the servo fell silent the bus is left alone this long (reads report "no answer" at once, writes are
 * skipped), so an absent or unpowered servo costs one 1-2 ms wait per retry instead of one per 10 ms. */
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

/* Wheel-mode setup, one bus transaction per background pass (at most RW_SPINDLE_SETUP_TIMEOUT_MS each). */
enum rw_spindle_setup_step {
    RW_SPINDLE_SETUP_DONE = 0,
    RW_SPINDLE_SETUP_TORQUE_OFF,
    RW_SPINDLE_SETUP_READ_EEPROM,     /* return delay and both angle limits */
    RW_SPINDLE_SETUP_RETURN_DELAY,    /* written only if it is not 0 (EEPROM) */
    RW_SPINDLE_SETUP_ANGLE_LIMITS,    /* written only if they are not 0 (EEPROM) */
    RW_SPINDLE_SETUP_STOP,            /* moving speed 0 */
    RW_SPINDLE_SETUP_TORQUE_ON,
};

struct rw_arduino_spindle {
    rw_spindle_exchange exchange; /* shared with the tick (the core's rw_hal_spindle calls) */
    uint8_t setup_step;       /* rw_spindle_setup_step: wheel mode being set up (DONE: configured) */
    uint8_t eeprom[5];        /* return delay, CW limit (2), CCW limit (2), as read by the setup */
    bool silent;              /* RW_SPINDLE_SILENT_AFTER_FAILURES reads unanswered: retry after RW_SPINDLE_RETRY_MS */
    uint8_t failed_in_a_row;  /* unanswered reads since the last answered one */
    uint32_t silent_since_ms;
    uint32_t last_setup_ms;   /* a failed setup starts again at most every RW_SPINDLE_RETRY_MS */
    uint32_t transactions;    /* bus transactions made (each bounded by its timeout) */
    uint32_t timeouts;        /* transactions without a valid status packet */
    uint32_t skipped_silent;  /* jobs answered without the bus while the servo is silent */
    uint32_t setups;          /* wheel-mode setups completed (boot, and after each silence) */
    uint32_t eeprom_writes;   /* EEPROM registers rewritten by a setup (0 once the servo is configured) */
    uint32_t max_transaction_us; /* longest transaction, micros() */
};

/* Serial1 at 1 Mbps, Protocol 1.0, limit switch pin; the wheel-mode setup runs from the first service call. */
void rw_arduino_spindle_begin(rw_arduino_spindle *sp);

/* Background loop: at most one bus transaction (a setup step, the posted write, or the requested read), at
 * most RW_SPINDLE_SETUP_TIMEOUT_MS long. Never call from the tick. */
void rw_arduino_spindle_service(rw_arduino_spindle *sp, uint32_t now_ms);

/* The tick's side: rw_hal_spindle over the exchange. */
rw_hal_spindle rw_arduino_spindle_hal(rw_arduino_spindle *sp);

#endif /* RW_ARDUINO_SPINDLE_H */
