/* FlashStorage's FlashClass over an aligned array of our own (the library's Flash() macro does the same),
 * so that the read-back check can address the area; every access goes through FlashClass (another
 * translation unit), never through the array, whose initializer the compiler would otherwise fold. */
#include "arduino_config_store.h"

#include <Arduino.h>
#include <FlashStorage.h>
#include <string.h>

static_assert(sizeof(rw_config) % 4u == 0u, "FlashClass writes whole 32-bit words");

namespace {

/* Zero in the image: a record never written reads as blank. Whole rows (256 bytes on the SAMD21G18). */
__attribute__((__aligned__(256))) const uint8_t config_area[RW_CONFIG_AREA_BYTES] = {};

FlashClass config_flash(config_area, RW_CONFIG_AREA_BYTES);

const uint32_t VERIFY_CHUNK_BYTES = 32u;

bool blank(const uint8_t *bytes, size_t len)
{
    bool zeros = true;
    bool ones = true;
    for (size_t i = 0u; i < len; ++i) {
        zeros = zeros && bytes[i] == 0x00u;
        ones = ones && bytes[i] == 0xFFu;
    }
    return zeros || ones;
}

bool store_load(void *ctx, void *buf, size_t len)
{
    rw_arduino_config_store *store = static_cast<rw_arduino_config_store *>(ctx);
    if (len == 0u || len > RW_CONFIG_AREA_BYTES) {
        return false;
    }
    config_flash.read(config_area, buf, static_cast<uint32_t>(len));
    if (blank(static_cast<const uint8_t *>(buf), len)) {
        return false;
    }
    ++store->loads;
    return true;
}

bool store_save(void *ctx, const void *buf, size_t len)
{
    rw_arduino_config_store *store = static_cast<rw_arduino_config_store *>(ctx);
    if (len == 0u || len > RW_CONFIG_AREA_BYTES || len % 4u != 0u) {
        ++store->save_failures;
        return false;
    }
    config_flash.erase(config_area, static_cast<uint32_t>(len));
    config_flash.write(config_area, buf, static_cast<uint32_t>(len));
    const uint8_t *want = static_cast<const uint8_t *>(buf);
    uint8_t got[VERIFY_CHUNK_BYTES];
    for (size_t off = 0u; off < len; off += VERIFY_CHUNK_BYTES) {
        const size_t n = len - off < VERIFY_CHUNK_BYTES ? len - off : VERIFY_CHUNK_BYTES;
        config_flash.read(config_area + off, got, static_cast<uint32_t>(n));
        if (memcmp(got, want + off, n) != 0) {
            ++store->save_failures;
            return false;
        }
    }
    ++store->saves;
    return true;
}

/* From the tick (TC3 interrupt): a copy and a flag; the background loop writes while status is BUSY and
 * never touches pending otherwise, the tick never while it is. */
bool store_request_save(void *ctx, const void *buf, size_t len)
{
    rw_arduino_config_store *store = static_cast<rw_arduino_config_store *>(ctx);
    if (store->status == RW_CONFIG_SAVE_BUSY || len != sizeof store->pending) {
        ++store->refused_busy;
        return false;
    }
    memcpy(&store->pending, buf, len);
    ++store->requests;
    __DMB(); /* the copy is complete before the background loop can see BUSY */
    store->status = RW_CONFIG_SAVE_BUSY;
    return true;
}

uint8_t store_save_status(void *ctx)
{
    const rw_arduino_config_store *store = static_cast<const rw_arduino_config_store *>(ctx);
    return store->status;
}

} // namespace

rw_hal_config_store rw_arduino_config_store_hal(rw_arduino_config_store *store)
{
    store->status = RW_CONFIG_SAVE_IDLE;
    rw_hal_config_store hal;
    hal.ctx = store;
    hal.load = store_load;
    hal.save = store_save;
    hal.request_save = store_request_save;
    hal.save_status = store_save_status;
    return hal;
}

void rw_arduino_config_store_service(rw_arduino_config_store *store, bool rope_down)
{
    if (store->status != RW_CONFIG_SAVE_BUSY) {
        return;
    }
    if (!rope_down) { /* the core refuses ARM while a commit is BUSY: this is the second gate, never expected */
        ++store->deferred_passes;
        return;
    }
    const uint32_t start_us = micros();
    const bool ok = store_save(store, &store->pending, sizeof store->pending);
    const uint32_t took_us = micros() - start_us;
    if (took_us > store->max_save_us) {
        store->max_save_us = took_us;
    }
    __DMB();
    store->status = ok ? RW_CONFIG_SAVE_DONE : RW_CONFIG_SAVE_FAILED;
}
