#include "sil_config_store.h"

#include <stdio.h>
#include <string.h>

static bool load(void *ctx, void *buf, size_t len)
{
    const sil_config_store *s = ctx;
    FILE *f = fopen(s->path, "rb");
    if (f == NULL) {
        return false;
    }
    size_t n = fread(buf, 1, len, f);
    int extra = fgetc(f);
    fclose(f);
    return n == len && extra == EOF;
}

static bool save(void *ctx, const void *buf, size_t len)
{
    const sil_config_store *s = ctx;
    char tmp[sizeof s->path + 8];
    snprintf(tmp, sizeof tmp, "%s.tmp", s->path);
    FILE *f = fopen(tmp, "wb");
    if (f == NULL) {
        return false;
    }
    bool ok = fwrite(buf, 1, len, f) == len;
    ok = (fclose(f) == 0) && ok;
    return ok && rename(tmp, s->path) == 0;
}

static bool request_save(void *ctx, const void *buf, size_t len)
{
    sil_config_store *s = ctx;
    if (s->status == RW_CONFIG_SAVE_BUSY || len != sizeof s->pending) {
        ++s->refused_busy;
        return false;
    }
    memcpy(&s->pending, buf, len);
    s->countdown = s->save_ticks;
    s->status = RW_CONFIG_SAVE_BUSY;
    ++s->requests;
    return true;
}

static uint8_t save_status(void *ctx)
{
    const sil_config_store *s = ctx;
    return s->status;
}

void sil_config_store_service(sil_config_store *s)
{
    if (s->status != RW_CONFIG_SAVE_BUSY) {
        return;
    }
    if (s->countdown > 1u) {
        --s->countdown;
        return;
    }
    const bool ok = save(s, &s->pending, sizeof s->pending);
    s->status = ok ? RW_CONFIG_SAVE_DONE : RW_CONFIG_SAVE_FAILED;
    if (ok) {
        ++s->writes_ok;
    } else {
        ++s->writes_failed;
    }
}

rw_hal_config_store sil_config_store_hal(sil_config_store *s)
{
    rw_hal_config_store hal = {
        .ctx = s, .load = load, .save = save, .request_save = request_save, .save_status = save_status,
    };
    return hal;
}
