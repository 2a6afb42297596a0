/* Hardware watchdog (SAMD21 WDT) and the reset cause read at boot. */
#ifndef RW_ARDUINO_WATCHDOG_H
#define RW_ARDUINO_WATCHDOG_H

#include <stdint.h>

/* Reset cause bits (SAMD21 PM->RCAUSE). */
enum rw_reset_cause {
    RW_RESET_CAUSE_POWER_ON = 0x01u,
    RW_RESET_CAUSE_BROWN_OUT_CORE = 0x02u, /* BOD12 */
    RW_RESET_CAUSE_BROWN_OUT_VDD = 0x04u,  /* BOD33 */
    RW_RESET_CAUSE_EXTERNAL = 0x10u,       /* reset pin (also the double-tap to the bootloader) */
    RW_RESET_CAUSE_WATCHDOG = 0x20u,
    RW_RESET_CAUSE_SOFTWARE = 0x40u,       /* NVIC_SystemReset, e.g. the upload tool's 1200-baud touch */
};

/* The reset cause of this boot (PM->RCAUSE, one rw_reset_cause bit). Valid from the first instruction. */
uint8_t rw_arduino_watchdog_reset_cause(void);

/* Start (or restart with a new period) the watchdog: a reset follows unless rw_arduino_watchdog_feed runs
 * at least every period_ms. Returns the period actually set (the WDT has power-of-two periods, 8 ms..16 s). */
uint32_t rw_arduino_watchdog_begin(uint32_t period_ms);

/* Restart the watchdog period without waiting: returns false (and does nothing) while the previous clear
 * is still synchronising into the WDT's 1 kHz clock domain, which takes a few milliseconds. */
bool rw_arduino_watchdog_feed(void);

/* A function WiFiNINA can call while it blocks in WiFi.begin (WiFi.setFeedWatchdogFunc). */
void rw_arduino_watchdog_feed_callback(void);

#endif /* RW_ARDUINO_WATCHDOG_H */
