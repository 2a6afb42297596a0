#include "rw_config.h"

#include <stddef.h>
#include <string.h>

/* The reflected CRC-32 of each 4-bit value (polynomial 0xEDB88320): two lookups a byte instead of eight
 * shift-and-xor steps (the record's CRC in a PROVISION_COMMIT's tick: ~22k Cortex-M0+ cycles bit by bit). */
static const uint32_t CRC32_NIBBLE[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
    0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu, 0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
};

uint32_t rw_crc32(const void *data, uint32_t len)
{
    const uint8_t *p = data;
    uint32_t crc = 0xFFFFFFFFu;
    for (uint32_t i = 0; i < len; ++i) {
        crc ^= p[i];
        crc = (crc >> 4) ^ CRC32_NIBBLE[crc & 0x0Fu];
        crc = (crc >> 4) ^ CRC32_NIBBLE[crc & 0x0Fu];
    }
    return ~crc;
}

void rw_config_defaults(rw_config *c)
{
    memset(c, 0, sizeof *c);
    c->magic = RW_CONFIG_MAGIC;
    c->version = RW_CONFIG_VERSION;
    c->size = (uint16_t)sizeof *c;
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        c->params[i] = rw_param_table[i].default_value;
    }
    rw_config_seal(c);
}

void rw_config_seal(rw_config *c)
{
    c->crc32 = rw_crc32(c, (uint32_t)offsetof(rw_config, crc32));
}

bool rw_config_valid(const rw_config *c)
{
    return c->magic == RW_CONFIG_MAGIC && c->version == RW_CONFIG_VERSION && c->size == sizeof *c &&
           c->session_epoch < RW_CONFIG_EPOCH_LIMIT && c->boot_counter <= RW_CONFIG_BOOT_COUNTER_MAX &&
           c->crc32 == rw_crc32(c, (uint32_t)offsetof(rw_config, crc32));
}

void rw_config_set_key(rw_config *c, const uint8_t key[RW_KEY_LEN])
{
    memcpy(c->key, key, RW_KEY_LEN);
    c->key_set = 1u;
    rw_config_seal(c);
}

void rw_config_set_params(rw_config *c, const float values[RW_PARAM_COUNT])
{
    memcpy(c->params, values, sizeof c->params);
    rw_config_seal(c);
}

uint32_t rw_config_session_id(const rw_config *c)
{
    return c->session_epoch + c->boot_counter;
}

bool rw_config_next_boot(rw_config *c)
{
    if (c->boot_counter >= RW_CONFIG_BOOT_COUNTER_MAX) {
        return false;
    }
    c->boot_counter += 1u;
    rw_config_seal(c);
    return true;
}

bool rw_config_new_epoch(rw_config *c, uint32_t session_epoch)
{
    if (session_epoch >= RW_CONFIG_EPOCH_LIMIT) {
        return false;
    }
    c->session_epoch = session_epoch;
    c->boot_counter = 0u;
    c->commits += 1u;
    rw_config_seal(c);
    return true;
}

void rw_config_clear_key(rw_config *c)
{
    memset(c->key, 0, RW_KEY_LEN);
    c->key_set = 0u;
    rw_config_seal(c);
}

bool rw_config_commit(rw_config *c, uint32_t session_epoch, const float values[RW_PARAM_COUNT],
                      const uint8_t key[RW_KEY_LEN])
{
    if (session_epoch >= RW_CONFIG_EPOCH_LIMIT) {
        return false;
    }
    c->session_epoch = session_epoch;
    c->boot_counter = 0u;
    c->commits += 1u;
    memcpy(c->params, values, sizeof c->params);
    if (key != NULL) {
        memcpy(c->key, key, RW_KEY_LEN);
        c->key_set = 1u;
    }
    rw_config_seal(c);
    return true;
}

bool rw_config_take_credentials(const rw_config *c, char ssid[RW_CONFIG_SSID_LEN],
                                char password[RW_CONFIG_PASSWORD_LEN])
{
    char new_ssid[RW_CONFIG_SSID_LEN];
    char new_password[RW_CONFIG_PASSWORD_LEN];
    memcpy(new_ssid, c->wifi_ssid, sizeof new_ssid);
    memcpy(new_password, c->wifi_password, sizeof new_password);
    new_ssid[sizeof new_ssid - 1u] = '\0';
    new_password[sizeof new_password - 1u] = '\0';
    if (c->password_set == 0u) {
        new_password[0] = '\0';
    }
    const bool changed = strcmp(new_ssid, ssid) != 0 || strcmp(new_password, password) != 0;
    memcpy(ssid, new_ssid, sizeof new_ssid);
    memcpy(password, new_password, sizeof new_password);
    return changed;
}
