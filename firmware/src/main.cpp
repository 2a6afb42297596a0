/* Arduino entry for the MKR WiFi 1010: wires the arduino HAL (firmware/hal/arduino) to the firmware core.
 *
 * Two contexts (docs/board.md, "Tick and background loop"):
 *  - the control tick, in the TC3 interrupt every 1 ms: the ESC pulse staged by the previous tick is applied,
 *    the encoder latched, rw_core_tick run, the watchdog fed. It never waits on a bus: the core's link and
 *    spindle calls only move frames and readings through RAM (the HAL's queues and split transaction).
 *  - the background loop (loop()): the spindle's bus transactions, WiFiNINA, USB serial, a PROVISION_COMMIT's
 *    flash write (the core answers the command once it is done), the status LED and the USB status lines, each
 *    bounded; WiFi connection steps and the flash write only while the rope is down.
 *
 * setup: watchdog (long period while booting) -> core -> ESC PWM at the protocol's bottom pulse (the ESCs
 * start arming on it) -> encoder, battery, LED, USB serial, spindle -> HAL wired -> the core's first tick,
 * which loads the configuration record through hal.config and writes it back with the boot counter raised ->
 * WiFi with the record's credentials (NINA reset and ready line awaited at most 2 s, then blocking at most
 * RW_LINK_BOOT_CONNECT_TIMEOUT_MS, watchdog fed) -> watchdog at its running period -> 1 kHz tick interrupt. */
#include <Arduino.h>
#include <string.h>

extern "C" {
#include "rw_core.h"
#include "rw_defaults.h"
}

#include "arduino_battery.h"
#include "arduino_board.h"
#include "arduino_board_report.h"
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
/* The tick feeds the watchdog while the background loop has made a pass within this many ticks, or while the
 * rope is driven (a stalled background loop passes no host frame: the core lands the rope on heartbeat loss,
 * then the watchdog resets the board). */
const uint32_t BACKGROUND_STALL_TICKS = 100u;

rw_core core;
rw_arduino_esc_output esc;
rw_arduino_encoder encoder;
rw_arduino_battery battery;
rw_arduino_link link;
rw_arduino_serial_link serial_link;
rw_arduino_spindle spindle;
rw_arduino_config_store config_store;
rw_arduino_board_report report;

rw_hal_esc_output esc_hal;
rw_hal_encoder encoder_hal;
rw_hal_battery battery_hal;
rw_hal_link link_hal;
rw_hal_link serial_hal;
rw_hal_scheduler scheduler_hal;
rw_hal_spindle spindle_hal;
rw_hal_config_store config_hal;
rw_hal hal;

uint32_t link_commits;      /* background: core.state.config.commits the WiFi link's credentials were taken at */
rw_config committed_config; /* background: copy of the core's record, taken with the tick masked */
volatile uint32_t background_passes;
uint32_t tick_seen_passes;  /* tick: background_passes at the last change it saw */
uint32_t tick_stalled;      /* tick: ticks since background_passes last changed */

/* States that drive the rope: connection steps wait for the others. */
bool rope_down(uint8_t state)
{
    return state != RW_STATE_SPINUP && state != RW_STATE_AIRBORNE && state != RW_STATE_SPINDOWN &&
           state != RW_STATE_RELAX;
}

/* The core's state, read by the background loop (a byte the tick writes: one load). */
uint8_t core_state_now()
{
    return *static_cast<volatile const uint8_t *>(&core.state.state);
}

/* The control tick (TC3 interrupt). */
void control_tick()
{
    rw_arduino_esc_output_apply(&esc);
    const uint32_t now_us = rw_arduino_encoder_latch(&encoder);
    rw_core_tick(&core, &hal, now_us);
    const uint32_t passes = background_passes;
    if (passes != tick_seen_passes) {
        tick_seen_passes = passes;
        tick_stalled = 0u;
    } else if (tick_stalled < BACKGROUND_STALL_TICKS) {
        ++tick_stalled;
    }
    if (tick_stalled < BACKGROUND_STALL_TICKS || !rope_down(core.state.state)) {
        (void)rw_arduino_watchdog_feed();
    }
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
    rw_arduino_spindle_begin(&spindle); /* wheel mode is set up by the background loop */

    esc_hal = rw_arduino_esc_output_hal(&esc);
    encoder_hal = rw_arduino_encoder_hal(&encoder);
    battery_hal = rw_arduino_battery_hal(&battery);
    link_hal = rw_arduino_link_hal(&link); /* its queues are empty until the link begins */
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
     * credentials; the next tick follows the WiFi connection, up to 17 s later (DISARMED meanwhile). */
    rw_core_tick(&core, &hal, rw_arduino_encoder_latch(&encoder));
    link_commits = core.state.config.commits;
    (void)rw_arduino_link_begin(&link, &core.state.config, RW_LINK_UDP_PORT);
    rw_arduino_board_report_begin(&report, millis());

    (void)rw_arduino_watchdog_begin(RUN_WATCHDOG_MS); /* before the tick starts feeding it */
    rw_arduino_scheduler_begin(control_tick);
}

void loop()
{
    const uint32_t start_us = micros();
    const uint32_t now_ms = millis();
    const bool down = rope_down(core_state_now());
    rw_arduino_spindle_service(&spindle, now_ms);
    rw_arduino_link_service(&link, now_ms, down);
    rw_arduino_serial_link_service(&serial_link);
    rw_arduino_config_store_service(&config_store, down); /* a PROVISION_COMMIT's flash write, rope down only */
    if (down) {
        /* a PROVISION_COMMIT (DISARMED only): the committed record, copied with the tick kept out */
        rw_arduino_scheduler_mask_tick();
        const bool committed = core.state.config.commits != link_commits;
        if (committed) {
            memcpy(&committed_config, &core.state.config, sizeof committed_config);
        }
        rw_arduino_scheduler_unmask_tick();
        if (committed) {
            link_commits = committed_config.commits;
            rw_arduino_link_reconfigure(&link, &committed_config);
        }
    }
    rw_arduino_status_led_update(now_ms, rw_arduino_link_state(&link));
    rw_arduino_board_report_service(&report, now_ms, &serial_link, &link, &spindle);
    background_passes = background_passes + 1u;
    const uint32_t took_us = micros() - start_us;
    if (took_us > report.max_pass_us) {
        report.max_pass_us = took_us;
    }
}
