/* The device configuration kept in flash: one versioned record with a CRC-32.
 *
 * It holds what must survive a power cycle: the link key (provisioned over USB serial only), the WiFi
 * credentials (read by the board's link at boot), the parameters, the session epoch and the boot counter.
 * A record with another version, size or a bad CRC is ignored: defaults, no key (the device then takes
 * no command over WiFi until provisioned).
 *
 * Session ids (the freshness of the signed link, protocol/docs/security.md):
 *   session_id = session_epoch + boot_counter      (no wrap: epoch < 2^31 and boot_counter < 2^31)
 * session_epoch is a random 31-bit number the host draws from its CSPRNG at every PROVISION_COMMIT, which
 * also restarts boot_counter at 0; every boot adds one. Within a provisioning the ids grow strictly (frames
 * of an earlier boot never count again); a firmware upload erases flash and so the counter, but the next
 * provisioning starts from a fresh random epoch, so the ids of two provisionings with the same key are two
 * ranges at random places in 2^31: they meet with a probability of (n1 + n2) / 2^31 for n1 and n2 boots
 * (1e4 boots each: 9e-6). After RW_CONFIG_BOOT_COUNTER_MAX boots (68 years at one boot a second) the
 * device forgets its key rather than wrap: it takes nothing over WiFi until provisioned again. */
#ifndef RW_CONFIG_H
#define RW_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_protocol.h"

#define RW_CONFIG_MAGIC 0x46435752u /* "RWCF" */
#define RW_CONFIG_VERSION 2u /* 2: session_epoch */
#define RW_CONFIG_SSID_LEN 33u
#define RW_CONFIG_PASSWORD_LEN 64u
/* session_epoch < this (2^31); boot_counter never goes past RW_CONFIG_BOOT_COUNTER_MAX (2^31 - 1): their
 * sum, the session id, never wraps. */
#define RW_CONFIG_EPOCH_LIMIT 0x80000000u
#define RW_CONFIG_BOOT_COUNTER_MAX 0x7FFFFFFFu

typedef struct rw_config {
    uint32_t magic;
    uint16_t version;
    uint16_t size;          /* sizeof(rw_config) */
    uint32_t boot_counter;  /* boots since the last PROVISION_COMMIT (< 2^31) */
    uint32_t commits;       /* writes by PROVISION_COMMIT (flash wear) */
    uint32_t session_epoch; /* random base of this provisioning's session ids (< 2^31), from the host */
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
/* True when magic, version, size and CRC match and epoch and boot counter are in range (the record can be
 * trusted). */
bool rw_config_valid(const rw_config *c);
/* Recompute the CRC after a change. */
void rw_config_seal(rw_config *c);
/* Store the parameter values (RW_PARAM_COUNT floats, SI) and reseal. */
void rw_config_set_params(rw_config *c, const float values[RW_PARAM_COUNT]);
/* Store a link key (key_set = 1) and reseal. */
void rw_config_set_key(rw_config *c, const uint8_t key[RW_KEY_LEN]);
/* The session id of the boot the record describes: session_epoch + boot_counter. */
uint32_t rw_config_session_id(const rw_config *c);
/* A new boot: boot_counter + 1 and reseal; returns false (nothing changed) when the counter is at
 * RW_CONFIG_BOOT_COUNTER_MAX: the session ids of this provisioning are used up. */
bool rw_config_next_boot(rw_config *c);
/* A provisioning commit: a new epoch (< RW_CONFIG_EPOCH_LIMIT, else false and nothing changed), the boot
 * counter back to 0, commits + 1, resealed. */
bool rw_config_new_epoch(rw_config *c, uint32_t session_epoch);
/* A provisioning commit in one piece: rw_config_new_epoch, rw_config_set_params and (key != NULL)
 * rw_config_set_key with one CRC (the bitwise CRC-32 of the record is ~10k Cortex-M0+ cycles: once, not
 * three times, in the tick that takes PROVISION_COMMIT). false, nothing changed, for an epoch out of range. */
bool rw_config_commit(rw_config *c, uint32_t session_epoch, const float values[RW_PARAM_COUNT],
                      const uint8_t key[RW_KEY_LEN]);
/* Forget the link key (zeroed, key_set = 0) and reseal. */
void rw_config_clear_key(rw_config *c);
/* The record's WiFi credentials into ssid and password, NUL-terminated (an unset password is empty), as a link
 * uses them; true if they differ from what the two buffers held (the link must connect again). */
bool rw_config_take_credentials(const rw_config *c, char ssid[RW_CONFIG_SSID_LEN],
                                char password[RW_CONFIG_PASSWORD_LEN]);
/* CRC-32 (IEEE 802.3, reflected, init and final xor 0xFFFFFFFF). */
uint32_t rw_crc32(const void *data, uint32_t len);

#ifdef __cplusplus
}
#endif

#endif /* RW_CONFIG_H */
