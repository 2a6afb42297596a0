/* FlashStorage keeps one T in a 256-byte-aligned array in flash (erase by row, write by page).
 * Note: the array is part of the program image, so every firmware upload erases the stored configuration
 * (FlashStorage's documented limitation); the board then boots unprovisioned until provisioned again. */
#include "arduino_config_store.h"

#include <FlashStorage.h>
#include <stddef.h>
#include <string.h>

#include "arduino_battery.h"

extern "C" {
#include "rw_protocol.h"
}

namespace {

FlashStorage(rw_config_flash, rw_board_config);

uint16_t config_crc(const rw_board_config *cfg)
{
    return rw_crc16_ccitt(0xFFFFu, reinterpret_cast<const uint8_t *>(cfg), offsetof(rw_board_config, crc));
}

} // namespace

void rw_arduino_config_defaults(rw_board_config *cfg)
{
    memset(cfg, 0, sizeof *cfg); /* also the padding, so the CRC covers defined bytes */
    cfg->magic = RW_CONFIG_MAGIC;
    cfg->version = RW_CONFIG_VERSION;
    cfg->size_bytes = static_cast<uint16_t>(sizeof(rw_board_config));
    cfg->udp_port = RW_CONFIG_DEFAULT_UDP_PORT;
    cfg->battery_full_scale_mv = RW_BATTERY_DEFAULT_FULL_SCALE_MV;
    cfg->param_count = static_cast<uint8_t>(RW_PARAM_COUNT);
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        cfg->params[i] = rw_param_table[i].default_value;
    }
    cfg->crc = config_crc(cfg);
}

rw_config_status rw_arduino_config_load(rw_board_config *cfg)
{
    rw_config_flash.read(cfg);
    rw_config_status status = RW_CONFIG_OK;
    if (cfg->magic != RW_CONFIG_MAGIC) {
        status = RW_CONFIG_BLANK;
    } else if (cfg->version != RW_CONFIG_VERSION || cfg->size_bytes != sizeof(rw_board_config) ||
               cfg->param_count != RW_PARAM_COUNT) {
        status = RW_CONFIG_BAD_VERSION;
    } else if (cfg->crc != config_crc(cfg)) {
        status = RW_CONFIG_BAD_CRC;
    }
    if (status != RW_CONFIG_OK) {
        rw_arduino_config_defaults(cfg);
        return status;
    }
    cfg->wifi_ssid[RW_CONFIG_SSID_MAX] = '\0';
    cfg->wifi_password[RW_CONFIG_PASSWORD_MAX] = '\0';
    return RW_CONFIG_OK;
}

void rw_arduino_config_save(rw_board_config *cfg)
{
    cfg->magic = RW_CONFIG_MAGIC;
    cfg->version = RW_CONFIG_VERSION;
    cfg->size_bytes = static_cast<uint16_t>(sizeof(rw_board_config));
    cfg->param_count = static_cast<uint8_t>(RW_PARAM_COUNT);
    cfg->crc = config_crc(cfg);
    rw_config_flash.write(*cfg);
}

uint8_t rw_arduino_config_apply_params(const rw_board_config *cfg, rw_core *core)
{
    uint8_t refused = 0u;
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        if (rw_core_set_param(core, static_cast<uint8_t>(i), cfg->params[i]) != RW_DECODE_OK) {
            ++refused;
        }
    }
    return refused;
}

bool rw_arduino_config_has_wifi(const rw_board_config *cfg)
{
    return cfg->wifi_ssid[0] != '\0';
}
