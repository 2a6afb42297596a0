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

rw_hal_config_store sil_config_store_hal(sil_config_store *s)
{
    rw_hal_config_store hal = { .ctx = s, .load = load, .save = save };
    return hal;
}
