/* The device configuration kept in flash: one versioned record with a CRC-32.
 *
 * It holds what must survive a power cycle: the link key (provisioned over USB serial only), the WiFi
 * credentials (read by the board's link at boot), the parameters, and the boot counter, which is the
 * session id of the signed link (it grows at every boot, so frames of an earlier boot never count again).
 * A record with another version, size or a bad CRC is ignored: defaults, no key (the device then takes
 * no command over WiFi until provisioned). */
#ifndef RW_CONFIG_H
#define RW_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_protocol.h"

#define RW_CONFIG_MAGIC 0x46435752u /* "RWCF" */
#define RW_CONFIG_VERSION 1u
#define RW_CONFIG_SSID_LEN 33u
#define RW_CONFIG_PASSWORD_LEN 64u

typedef struct rw_config {
    uint32_t magic;
    uint16_t version;
    uint16_t size;          /* sizeof(rw_config) */
    uint32_t boot_counter;  /* session id of the current boot */
    uint32_t commits;       /* writes by PROVISION_COMMIT (flash wear) */
    uint8_t key[RW_KEY_LEN];
    uint8_t key_set;
    uint8_t password_set;
    uint8_t reserved[2];
    char wifi_ssid[RW_CONFIG_SSID_LEN];
    char wifi_password[RW_CONFIG_PASSWORD_LEN];
    uint8_t reserved2[3];
    float params[RW_PARAM_COUNT];
    uint32_t crc32;         /* over every byte before it */
} rw_config;

#ifdef __cplusplus
extern "C" {
#endif

void rw_config_defaults(rw_config *c);
/* True when magic, version, size and CRC match (the record can be trusted). */
bool rw_config_valid(const rw_config *c);
/* Recompute the CRC after a change. */
void rw_config_seal(rw_config *c);
/* Store the parameter values (RW_PARAM_COUNT floats, SI) and reseal. */
void rw_config_set_params(rw_config *c, const float values[RW_PARAM_COUNT]);
/* Store a link key (key_set = 1) and reseal. */
void rw_config_set_key(rw_config *c, const uint8_t key[RW_KEY_LEN]);
/* CRC-32 (IEEE 802.3, reflected, init and final xor 0xFFFFFFFF). */
uint32_t rw_crc32(const void *data, uint32_t len);

#ifdef __cplusplus
}
#endif

#endif /* RW_CONFIG_H */
