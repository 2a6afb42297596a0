#include "rw_config.h"

#include <stddef.h>
#include <string.h>

uint32_t rw_crc32(const void *data, uint32_t len)
{
    const uint8_t *p = data;
    uint32_t crc = 0xFFFFFFFFu;
    for (uint32_t i = 0; i < len; ++i) {
        crc ^= p[i];
        for (int bit = 0; bit < 8; ++bit) {
            crc = (crc & 1u) != 0u ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
        }
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
