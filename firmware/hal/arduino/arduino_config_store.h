/* Board configuration in flash: WiFi credentials, UDP port, battery calibration, link key and the device
 * parameters as one versioned struct with a CRC, stored with FlashStorage (cmaglie/FlashStorage).
 *
 * Provisioning (writing SSID, password and key over USB Serial) is a later step: this file only defines the
 * struct and loads/saves it. Parameters changed with PARAM_SET are not saved yet either (docs/board.md). */
#ifndef RW_ARDUINO_CONFIG_STORE_H
#define RW_ARDUINO_CONFIG_STORE_H

#include <stdint.h>

extern "C" {
#include "rw_core.h"
}

static const uint32_t RW_CONFIG_MAGIC = 0x46435752u; /* "RWCF" little-endian */
/* Bump on every layout or meaning change; an old struct is then refused and the defaults are used. */
static const uint16_t RW_CONFIG_VERSION = 1u;
static const uint16_t RW_CONFIG_DEFAULT_UDP_PORT = 14550u;
static const uint8_t RW_CONFIG_SSID_MAX = 32u;     /* IEEE 802.11 SSID, bytes */
static const uint8_t RW_CONFIG_PASSWORD_MAX = 63u; /* WPA2 passphrase, characters */
static const uint8_t RW_CONFIG_LINK_KEY_LEN = 32u; /* key of the authenticated protocol (not used yet) */

struct rw_board_config {
    uint32_t magic;                 /* RW_CONFIG_MAGIC */
    uint16_t version;               /* RW_CONFIG_VERSION */
    uint16_t size_bytes;            /* sizeof(rw_board_config): catches a layout change without a version bump */
    uint16_t udp_port;              /* UDP port the board listens on */
    uint16_t battery_full_scale_mv; /* battery mV at ADC full scale (divider x 3.3 V), see arduino_battery.h */
    char wifi_ssid[RW_CONFIG_SSID_MAX + 1u];         /* NUL-terminated; empty = not provisioned */
    char wifi_password[RW_CONFIG_PASSWORD_MAX + 1u]; /* NUL-terminated; empty = open network */
    uint8_t link_key[RW_CONFIG_LINK_KEY_LEN];
    uint8_t param_count;            /* RW_PARAM_COUNT of the firmware that saved it */
    uint8_t reserved[3];            /* zero */
    float params[RW_PARAM_COUNT];   /* device parameters by rw_param_id, SI units as in the protocol spec */
    uint16_t crc;                   /* CRC-16/CCITT-FALSE over every byte before this field */
};

enum rw_config_status {
    RW_CONFIG_OK = 0,
    RW_CONFIG_BLANK = 1,       /* no struct stored (magic missing: never saved, or erased by an upload) */
    RW_CONFIG_BAD_VERSION = 2, /* stored by another layout version or size */
    RW_CONFIG_BAD_CRC = 3,     /* stored but corrupted */
};

/* Defaults: not provisioned (empty SSID), port 14550, the assumed divider, zero key, spec parameter defaults. */
void rw_arduino_config_defaults(rw_board_config *cfg);

/* Read the stored struct; on anything but RW_CONFIG_OK, cfg holds the defaults. */
rw_config_status rw_arduino_config_load(rw_board_config *cfg);

/* Write cfg (magic, version, size and CRC filled in here). Erases and writes one flash row set: a few ms,
 * and the flash endures about 25,000 writes: save on request only, never periodically. */
void rw_arduino_config_save(rw_board_config *cfg);

/* Give the stored parameters to the core through rw_core_set_param (same range checks as PARAM_SET);
 * returns how many the core refused (those keep their defaults). Call right after rw_core_init. */
uint8_t rw_arduino_config_apply_params(const rw_board_config *cfg, rw_core *core);

/* True when an SSID is stored. */
bool rw_arduino_config_has_wifi(const rw_board_config *cfg);

#endif /* RW_ARDUINO_CONFIG_STORE_H */
