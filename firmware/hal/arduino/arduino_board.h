/* Pin map and fixed facts of the Arduino MKR WiFi 1010 (SAMD21G18A, 48 MHz) as RoboWrangler wires it.
 * One place for every pin; docs/board.md has the same table with the wiring. */
#ifndef RW_ARDUINO_BOARD_H
#define RW_ARDUINO_BOARD_H

#include <Arduino.h>
#include <stdint.h>

/* ESCs: hardware PWM on TCC1, both channels share its 400 Hz period (see arduino_esc_output.cpp). */
static const uint8_t RW_PIN_ESC1 = 2u;           /* D2 = PA10, TCC1/WO[0] (peripheral E), CC0 */
static const uint8_t RW_PIN_ESC2 = 3u;           /* D3 = PA11, TCC1/WO[1] (peripheral E), CC1 */
/* Rope-drive encoder: one channel into an external interrupt (see arduino_encoder.cpp). */
static const uint8_t RW_PIN_ENCODER = 7u;        /* D7 = PA21, EIC EXTINT[5] */
/* Motor battery through a divider into the ADC (see arduino_battery.cpp). */
static const uint8_t RW_PIN_BATTERY = A1;        /* A1 = PB02, ADC AIN[10] */
static const uint8_t RW_ADC_BATTERY_AIN = 10u;   /* the ADC input PB02 is wired to */
/* Status LED (the board's yellow LED). */
static const uint8_t RW_PIN_STATUS_LED = LED_BUILTIN; /* D6 = PA20 */
/* DYNAMIXEL Shield for MKR (AX-12A spindle, see arduino_spindle.cpp): half-duplex TTL on Serial1 (D13 RX =
 * PB23, D14 TX = PB22, SERCOM5) with the direction pin on A6 (PA07), driven by Dynamixel2Arduino. */
static const uint8_t RW_PIN_DXL_DIR = A6;
/* Optional home limit switch of the spindle: normally open to GND, internal pull-up; closed = LOW. */
static const uint8_t RW_PIN_SPINDLE_HOME = 5u;   /* D5 = PB11, plain GPIO */

/* Control tick (TC3, see arduino_scheduler.cpp). */
static const uint32_t RW_TICK_PERIOD_US = 1000u;

#endif /* RW_ARDUINO_BOARD_H */
