/* Arduino entry for the MKR WiFi 1010: wires the arduino HAL (firmware/hal/arduino) to the firmware core.
 *
 * setup: watchdog (long period while booting) -> configuration from flash -> core with the stored
 * parameters -> ESC PWM at the minimum pulse (the ESCs start arming on it) -> encoder, battery, LED ->
 * WiFi (blocking at most RW_LINK_BOOT_CONNECT_TIMEOUT_MS, watchdog fed) -> 1 kHz tick timer -> watchdog
 * at its running period.
 * loop: on each tick flag, latch the encoder with the tick time, run rw_core_tick, feed the watchdog,
 * service the WiFi connection (reconnects only while the ESCs are at idle) and the status LED. */
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
#include "arduino_status_led.h"
#include "arduino_watchdog.h"

namespace {

const uint32_t BOOT_WATCHDOG_MS = 4000u; /* covers the NINA reset (~0.75 s) between WiFiNINA's own feeds */
const uint32_t RUN_WATCHDOG_MS = 250u;   /* 250 missed ticks */
const uint16_t ESC_FALLBACK_MIN_US = 1000u;

rw_core core;
rw_board_config config;
rw_arduino_esc_output esc;
rw_arduino_encoder encoder;
rw_arduino_battery battery;
rw_arduino_link link;

rw_hal_esc_output esc_hal;
rw_hal_encoder encoder_hal;
rw_hal_battery battery_hal;
rw_hal_link link_hal;
rw_hal_scheduler scheduler_hal;
rw_hal hal;

uint8_t reset_cause; /* PM->RCAUSE of this boot, reported in the core's BOOT event */
rw_config_status config_status;

bool esc_at_idle(uint8_t state)
{
    return state != RW_STATE_SPINUP && state != RW_STATE_AIRBORNE && state != RW_STATE_SPINDOWN;
}

} // namespace

void setup()
{
    reset_cause = rw_arduino_watchdog_reset_cause();
    (void)rw_arduino_watchdog_begin(BOOT_WATCHDOG_MS);

    config_status = rw_arduino_config_load(&config);
    rw_core_init(&core);
    core.reset_cause = reset_cause;
    (void)rw_arduino_config_apply_params(&config, &core);

    const uint16_t esc_min_us = static_cast<uint16_t>(rw_params_get(&core.params, RW_PARAM_ESC_MIN_US));
    if (!rw_arduino_esc_output_begin(&esc, esc_min_us, RW_ESC_PULSE_LIMIT_HIGH_US)) {
        (void)rw_arduino_esc_output_begin(&esc, ESC_FALLBACK_MIN_US, RW_ESC_PULSE_LIMIT_HIGH_US);
    }
    rw_arduino_status_led_begin();
    rw_arduino_encoder_begin(&encoder);
    rw_arduino_battery_begin(&battery, config.battery_full_scale_mv);
    (void)rw_arduino_link_begin(&link, config.wifi_ssid, config.wifi_password, config.udp_port);

    esc_hal = rw_arduino_esc_output_hal(&esc);
    encoder_hal = rw_arduino_encoder_hal(&encoder);
    battery_hal = rw_arduino_battery_hal(&battery);
    link_hal = rw_arduino_link_hal(&link);
    scheduler_hal = rw_arduino_scheduler_hal();
    hal.esc = &esc_hal;
    hal.encoder = &encoder_hal;
    hal.battery = &battery_hal;
    hal.link = &link_hal;
    hal.scheduler = &scheduler_hal;

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

    const uint32_t now_ms = millis();
    rw_arduino_link_service(&link, now_ms, esc_at_idle(rw_core_state(&core)));
    rw_arduino_status_led_update(now_ms, static_cast<rw_link_state>(link.state));
    rw_arduino_scheduler_end_tick();
}
