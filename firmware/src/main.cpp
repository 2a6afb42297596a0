/* Arduino entry for the MKR WiFi 1010: wires the arduino HAL (firmware/hal/arduino) to the firmware core.
 *
 * setup: watchdog (long period while booting) -> core -> ESC PWM at the protocol's bottom pulse (the ESCs
 * start arming on it) -> encoder, battery, LED, USB serial, spindle (wheel mode) -> HAL wired -> the
 * core's first tick, which loads the configuration record through hal.config and writes it back with the
 * boot counter raised (its parameters, key and WiFi credentials are the core's from then on) -> WiFi with
 * the record's credentials (blocking at most RW_LINK_BOOT_CONNECT_TIMEOUT_MS, watchdog fed) -> 1 kHz tick
 * timer -> watchdog at its running period.
 * loop: on each tick flag, latch the encoder with the tick time, run rw_core_tick, feed the watchdog,
 * hand the USB serial its next packet, follow a PROVISION_COMMIT with the WiFi link, service the WiFi
 * connection (reconnects only while the ESCs are at idle) and the status LED. */
#include <Arduino.h>

extern "C" {
#include "rw_core.h"
#include "rw_defaults.h"
}

#include "arduino_battery.h"
#include "arduino_board.h"
#include "arduino_config_store.h"
#include "arduino_encoder.h"
#include "arduino_esc_output.h"
#include "arduino_link.h"
#include "arduino_scheduler.h"
#include "arduino_serial_link.h"
#include "arduino_spindle.h"
#include "arduino_status_led.h"
#include "arduino_watchdog.h"

namespace {

const uint32_t BOOT_WATCHDOG_MS = 4000u; /* covers the NINA reset (~0.75 s) between WiFiNINA's own feeds */
const uint32_t RUN_WATCHDOG_MS = 250u;   /* 250 missed ticks */

rw_core core;
rw_arduino_esc_output esc;
rw_arduino_encoder encoder;
rw_arduino_battery battery;
rw_arduino_link link;
rw_arduino_serial_link serial_link;
rw_arduino_spindle spindle;
rw_arduino_config_store config_store;

rw_hal_esc_output esc_hal;
rw_hal_encoder encoder_hal;
rw_hal_battery battery_hal;
rw_hal_link link_hal;
rw_hal_link serial_hal;
rw_hal_scheduler scheduler_hal;
rw_hal_spindle spindle_hal;
rw_hal_config_store config_hal;
rw_hal hal;

uint32_t link_commits; /* core.state.config.commits the WiFi link's credentials were taken at */

bool esc_at_idle(uint8_t state)
{
    return state != RW_STATE_SPINUP && state != RW_STATE_AIRBORNE && state != RW_STATE_SPINDOWN;
}

} // namespace

void setup()
{
    const uint8_t reset_cause = rw_arduino_watchdog_reset_cause();
    (void)rw_arduino_watchdog_begin(BOOT_WATCHDOG_MS);

    rw_core_init(&core);
    core.reset_cause = reset_cause;

    /* The stored esc_min_us is known only after the core's first tick: until then the HAL floor is the
     * protocol's bottom (1000 us), which every valid esc_min_us is at or above; the core's idle pulse
     * follows the stored value from its first tick on. */
    (void)rw_arduino_esc_output_begin(&esc, RW_ESC_PULSE_LIMIT_LOW_US, RW_ESC_PULSE_LIMIT_HIGH_US);
    rw_arduino_status_led_begin();
    rw_arduino_encoder_begin(&encoder);
    rw_arduino_battery_begin(&battery, RW_BATTERY_DEFAULT_FULL_SCALE_MV);
    rw_arduino_serial_link_begin(&serial_link);
    (void)rw_arduino_spindle_begin(&spindle); /* no answer: retried from the spindle reads */

    esc_hal = rw_arduino_esc_output_hal(&esc);
    encoder_hal = rw_arduino_encoder_hal(&encoder);
    battery_hal = rw_arduino_battery_hal(&battery);
    link_hal = rw_arduino_link_hal(&link); /* not up yet: receives nothing, sends nowhere */
    serial_hal = rw_arduino_serial_link_hal(&serial_link);
    scheduler_hal = rw_arduino_scheduler_hal();
    spindle_hal = rw_arduino_spindle_hal(&spindle);
    config_hal = rw_arduino_config_store_hal(&config_store);
    hal.esc = &esc_hal;
    hal.encoder = &encoder_hal;
    hal.battery = &battery_hal;
    hal.link = &link_hal;
    hal.scheduler = &scheduler_hal;
    hal.spindle = &spindle_hal;
    hal.serial = &serial_hal;
    hal.config = &config_hal;

    /* First tick: the record is loaded (and saved with the new boot counter) before the WiFi link needs its
     * credentials; the next tick follows the WiFi connection, up to 15 s later (DISARMED meanwhile). */
    rw_core_tick(&core, &hal, rw_arduino_encoder_latch(&encoder));
    link_commits = core.state.config.commits;
    (void)rw_arduino_link_begin(&link, &core.state.config, RW_LINK_UDP_PORT);

    rw_arduino_scheduler_begin();
    (void)rw_arduino_watchdog_begin(RUN_WATCHDOG_MS);
}

void loop()
{
    if (!rw_arduino_scheduler_take_tick()) {
        return;
    }
    const uint32_t now_us = rw_arduino_encoder_latch(&encoder);
    rw_core_tick(&core, &hal, now_us);
    (void)rw_arduino_watchdog_feed();
    rw_arduino_serial_link_service(&serial_link);

    const uint32_t now_ms = millis();
    const bool idle = esc_at_idle(rw_core_state(&core));
    if (core.state.config.commits != link_commits && idle) {
        link_commits = core.state.config.commits;
        rw_arduino_link_reconfigure(&link, &core.state.config);
    }
    rw_arduino_link_service(&link, now_ms, idle);
    rw_arduino_status_led_update(now_ms, static_cast<rw_link_state>(link.state));
    rw_arduino_scheduler_end_tick();
}
