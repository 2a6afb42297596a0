/* The HAL the firmware core is given by reference: one small interface per header, gathered here.
 * Members added later go at the end, so that bindings that zero-fill what they do not know stay valid.
 * Implementations: hal/arduino/ (MKR WiFi 1010) and hal/sil/ (host process in lockstep with the plant). */
#ifndef RW_HAL_H
#define RW_HAL_H

#include "rw_hal_battery.h"
#include "rw_hal_config_store.h"
#include "rw_hal_encoder.h"
#include "rw_hal_esc_output.h"
#include "rw_hal_link.h"
#include "rw_hal_scheduler.h"
#include "rw_hal_spindle.h"

typedef struct rw_hal {
    const rw_hal_esc_output *esc;
    const rw_hal_encoder *encoder;
    const rw_hal_battery *battery;
    const rw_hal_link *link;
    const rw_hal_scheduler *scheduler;
    const rw_hal_spindle *spindle; /* NULL: no spindle fitted (spindle commands are refused) */
    const rw_hal_link *serial;     /* USB serial (COBS frames), trusted: unsigned frames and PROVISION_*; NULL: none */
    const rw_hal_config_store *config; /* NULL: nothing persists (session id 1 at every boot) */
} rw_hal;

#endif /* RW_HAL_H */
