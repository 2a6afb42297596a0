/* Fuzz target: the whole firmware core (rw_core_init, rw_core_tick) behind a fake HAL, on arbitrary bytes.
 *
 * Input layout (every byte sequence is a valid input; missing bytes read as absent):
 *   byte 0   options: OPT_* below (the stored configuration record, the config store, WiFi signing, the
 *            spindle, a pre-roll past the ESC arming hold)
 *   [record] with OPT_FUZZ_RECORD: the next sizeof(rw_config) bytes are the stored record (zero-padded);
 *            with OPT_SEAL_RECORD as well, the harness makes magic, version, size and CRC right, so the
 *            record's content (parameters, key, boot counter) reaches the core's checks
 *   chunks   [tag][len][len bytes] ... ; tag & 3: 0 = a datagram on USB serial (trusted), 1 = a datagram on
 *            WiFi (must be signed), 2 = a sensor event (battery mV u16, encoder flags, spindle flags,
 *            spindle load u16, limit switch, tick period us u16), 3 = with len >= 1: a replay on WiFi (an
 *            exact copy of the last signed datagram WiFi delivered), else nothing; then tag >> 2 ticks
 *            (v < 32: v ticks; else (v - 31) x 32 ticks). A datagram waits in its link's queue (4 deep)
 *            until a tick reads it (the core reads at most one per link and tick).
 * The plant: the rope speed follows the ESC pulse (first order, 50 ms), the encoder counts it (unless the
 * event says it is silent), an AX-12A stand-in integrates the commanded wheel speed; the tick clock starts
 * 200 ms before its 32-bit wrap.
 *
 * Invariants, checked on every call and tick (a violation traps; libFuzzer keeps the input):
 *   - the ESC pulse is always within [esc_min_us, 2000] (esc_min_us: the current parameter, >= 1000);
 *   - every frame the core emits decodes (rw_frame_decode OK, from an exactly sized heap copy), is a
 *     device-to-host message (reply, telemetry, event), is signed with the device's key on WiFi once a key
 *     is set and unsigned on serial, and never contains the link key;
 *   - over WiFi a frame that decodes but is not HELLO and not signed with the key gets no answer and does
 *     not become the peer; neither does an exact copy of a signed frame delivered before (a replay), also
 *     after a PROVISION_COMMIT of the same key (firmware/fuzz/crashes/README.md: found here, fixed);
 *   - at most one answer per link and tick; a queued frame only goes out in a tick without an answer;
 *   - every parameter is always within its range; the state is a known one;
 *   - the configuration the core writes is always a valid record; a stored record that is not valid
 *     leaves every parameter at its default and starts session 1. */
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_common.h"
#include "rw_config.h"
#include "rw_core.h"
#include "rw_protocol.h"

enum {
    OPT_FUZZ_RECORD = 0x01,  /* the stored record comes from the input */
    OPT_SEAL_RECORD = 0x02,  /* ... with magic, version, size and CRC made right */
    OPT_NO_STORE = 0x04,     /* hal->config == NULL */
    OPT_SAVE_FAILS = 0x08,   /* the store refuses every write */
    OPT_SIGN_WIFI = 0x10,    /* unsigned frames on WiFi are signed with the device's key, fresh counter */
    OPT_NO_SPINDLE = 0x20,   /* hal->spindle == NULL */
    OPT_PREROLL = 0x40,      /* 600 ticks before the first chunk (past the arming hold) */
    OPT_SESSION_STALE = 0x80 /* with OPT_SIGN_WIFI: sign for the previous session (must be dropped) */
};

/* A hook after every tick, for a debugging driver that includes this file (empty here). */
#ifndef RW_FUZZ_AFTER_TICK
#define RW_FUZZ_AFTER_TICK()
#endif

#define QUEUE_DEPTH 4u
#define DATAGRAM_MAX 255u
#define MAX_TICKS 30000u
#define START_US (0xFFFFFFFFu - 200000u)

static const uint8_t TEST_KEY[RW_KEY_LEN] = { 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15 };

typedef struct fake_link {
    rw_link_id id;
    uint8_t queue[QUEUE_DEPTH][DATAGRAM_MAX];
    size_t queue_len[QUEUE_DEPTH];
    bool queue_replay[QUEUE_DEPTH]; /* an exact copy of an earlier datagram: delivered as it is */
    unsigned head, count;
    bool has_peer;
    /* this tick */
    bool delivered;
    bool delivered_replay;
    uint8_t delivered_bytes[RW_MAX_FRAME_LEN + 1u];
    size_t delivered_len;   /* as the core decodes it: clamped to its buffer */
    unsigned replies, sends, accepts;
} fake_link;

static struct {
    rw_core core;
    uint8_t options;
    fake_link serial, wifi;
    /* plant */
    double rope_mps;
    double count_acc;
    uint32_t counts;
    uint32_t last_edge_us;
    uint32_t now_us;
    uint32_t tick_us;
    bool encoder_silent;
    uint16_t battery_mv;
    /* spindle stand-in */
    double spindle_pos;
    uint16_t spindle_raw_speed;
    uint16_t spindle_load_raw;
    bool spindle_silent;
    bool limit_switch;
    /* config store */
    rw_config stored;
    bool stored_present;
    bool record_was_valid;
    uint32_t record_boot_counter;
    uint32_t record_session_epoch;
    uint64_t sign_counter;
    uint8_t last_signed[RW_MAX_FRAME_LEN]; /* the last signed datagram WiFi delivered, for replays */
    size_t last_signed_len;
    unsigned ticks;
} h;


/* ---- output checks --------------------------------------------------------------------------------- */

/* The key-leak oracle is kept out of the fuzzer's comparison tracing (no_sanitize("coverage")): traced, its
 * memcmp handed libFuzzer the bytes of the device's own frames, which it then provisioned as the key, so
 * that an ACK "contained" the key (a crafted key equal to 16 bytes of a NACK: a false alarm, not a leak). */
#if defined(__clang__)
#define RW_FUZZ_ORACLE __attribute__((no_sanitize("coverage")))
#else
#define RW_FUZZ_ORACLE
#endif

RW_FUZZ_ORACLE static bool key_is_distinctive(const uint8_t *key)
{
    /* a key like all zeros would "appear" in any frame with 16 zero bytes: check only varied keys (a random
     * 128-bit key has 12 or more distinct bytes but with probability about 1e-4) */
    unsigned distinct = 0u;
    bool seen[256] = { false };
    for (unsigned i = 0u; i < RW_KEY_LEN; ++i) {
        if (!seen[key[i]]) {
            seen[key[i]] = true;
            ++distinct;
        }
    }
    return distinct >= 12u;
}

RW_FUZZ_ORACLE static bool contains(const uint8_t *hay, size_t n, const uint8_t *needle, size_t m)
{
    for (size_t i = 0u; i + m <= n; ++i) {
        uint8_t diff = 0u;
        for (size_t j = 0u; j < m; ++j) { /* not memcmp: libFuzzer intercepts memcmp whatever the attribute */
            diff |= (uint8_t)(hay[i + j] ^ needle[j]);
        }
        if (diff == 0u) {
            return true;
        }
    }
    return false;
}

static void check_outgoing(const fake_link *l, const uint8_t *frame, size_t len)
{
    RW_FUZZ_REQUIRE(len > 0u && len <= RW_MAX_FRAME_LEN);
    uint8_t *copy = rw_fuzz_exact_copy(frame, len);
    rw_frame f;
    RW_FUZZ_REQUIRE(rw_frame_decode(copy, len, &f) == RW_DECODE_OK);
    const rw_msg_info *info = rw_msg_info_find(f.msg_id);
    RW_FUZZ_REQUIRE(info->kind == RW_MSG_KIND_REPLY || info->kind == RW_MSG_KIND_TELEMETRY ||
                    info->kind == RW_MSG_KIND_EVENT || info->kind == RW_MSG_KIND_BURST);
    const rw_config *c = &h.core.state.config;
    bool is_signed = (f.flags & RW_FRAME_FLAG_SIGNED) != 0u;
    if (l->id == RW_LINK_WIFI && c->key_set != 0u) {
        RW_FUZZ_REQUIRE(is_signed && rw_frame_tag_valid(&f, c->key) == 1);
        RW_FUZZ_REQUIRE(f.session_id == rw_core_session_id(&h.core));
    } else {
        RW_FUZZ_REQUIRE(!is_signed);
    }
    if (c->key_set != 0u && key_is_distinctive(c->key)) {
        RW_FUZZ_REQUIRE(!contains(copy, len, c->key, RW_KEY_LEN));
    }
    if (h.core.state.key_staged && key_is_distinctive(h.core.state.staged_key)) {
        RW_FUZZ_REQUIRE(!contains(copy, len, h.core.state.staged_key, RW_KEY_LEN));
    }
    free(copy);
}

/* ---- fake HAL ---------------------------------------------------------------------------------------- */

static void maybe_sign_wifi(uint8_t *buf, size_t *len, size_t cap)
{
    const rw_config *c = &h.core.state.config;
    if ((h.options & OPT_SIGN_WIFI) == 0u || c->key_set == 0u) {
        return;
    }
    rw_frame f;
    if (rw_frame_decode(buf, *len, &f) != RW_DECODE_OK || (f.flags & RW_FRAME_FLAG_SIGNED) != 0u) {
        return;
    }
    uint32_t session = rw_core_session_id(&h.core) - ((h.options & OPT_SESSION_STALE) != 0u ? 1u : 0u);
    size_t n = rw_frame_sign(buf, *len, cap, session, ++h.sign_counter, c->key);
    if (n != 0u) {
        *len = n;
    }
}

static size_t link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    fake_link *l = ctx;
    while (l->count > 0u) {
        unsigned slot = l->head;
        l->head = (l->head + 1u) % QUEUE_DEPTH;
        --l->count;
        size_t n = l->queue_len[slot];
        if (n == 0u) {
            continue; /* an empty datagram reads as none */
        }
        uint8_t tmp[DATAGRAM_MAX + RW_SIGNATURE_LEN];
        memcpy(tmp, l->queue[slot], n);
        l->delivered_replay = l->queue_replay[slot];
        if (l->id == RW_LINK_WIFI && !l->delivered_replay) {
            maybe_sign_wifi(tmp, &n, sizeof tmp);
            rw_frame f;
            if (n <= sizeof h.last_signed && rw_frame_decode(tmp, n, &f) == RW_DECODE_OK &&
                (f.flags & RW_FRAME_FLAG_SIGNED) != 0u) {
                memcpy(h.last_signed, tmp, n);
                h.last_signed_len = n;
            }
        }
        size_t copied = n < cap ? n : cap;
        memcpy(buf, tmp, copied);
        l->delivered = true;
        l->delivered_len = copied < sizeof l->delivered_bytes ? copied : sizeof l->delivered_bytes;
        memcpy(l->delivered_bytes, tmp, l->delivered_len);
        return n > cap ? cap + 1u : n;
    }
    return 0u;
}

static void link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    fake_link *l = ctx;
    check_outgoing(l, frame, len);
    ++l->replies;
}

static void link_send(void *ctx, const uint8_t *frame, size_t len)
{
    fake_link *l = ctx;
    check_outgoing(l, frame, len);
    ++l->sends;
}

static void link_accept(void *ctx)
{
    fake_link *l = ctx;
    l->has_peer = true;
    ++l->accepts;
}

static uint16_t current_esc_min(void)
{
    return (uint16_t)h.core.params.value[RW_PARAM_ESC_MIN_US];
}

static void esc_write(void *ctx, uint16_t pulse_us)
{
    (void)ctx;
    uint16_t esc_min = current_esc_min();
    RW_FUZZ_REQUIRE(esc_min >= 1000u);
    RW_FUZZ_REQUIRE(pulse_us >= esc_min && pulse_us <= 2000u);
    /* the plant: 20 m/s at full throttle, first order with a 50 ms time constant */
    double target = (double)(pulse_us - 1000u) * 0.02;
    double dt_s = (double)h.tick_us * 1e-6;
    h.rope_mps += (target - h.rope_mps) * (dt_s >= 0.05 ? 1.0 : dt_s / 0.05);
}

static rw_encoder_sample encoder_read(void *ctx)
{
    (void)ctx;
    rw_encoder_sample s = { h.counts, h.last_edge_us };
    return s;
}

static uint16_t battery_read(void *ctx)
{
    (void)ctx;
    return h.battery_mv;
}

static uint32_t overruns(void *ctx)
{
    (void)ctx;
    return h.ticks / 1000u;
}

static bool spindle_read(void *ctx, rw_spindle_reading *out)
{
    (void)ctx;
    if (h.spindle_silent) {
        return false;
    }
    double pos = fmod(h.spindle_pos, 1024.0);
    if (pos < 0.0) {
        pos += 1024.0;
    }
    out->position_raw = (uint16_t)pos;
    out->speed_raw = h.spindle_raw_speed;
    out->load_raw = h.spindle_load_raw;
    out->limit_switch = h.limit_switch;
    return true;
}

static void spindle_write(void *ctx, uint16_t raw)
{
    (void)ctx;
    RW_FUZZ_REQUIRE(raw <= 2047u);
    h.spindle_raw_speed = raw;
}

static bool store_load(void *ctx, void *buf, size_t len)
{
    (void)ctx;
    RW_FUZZ_REQUIRE(len == sizeof(rw_config));
    if (!h.stored_present) {
        return false;
    }
    memcpy(buf, &h.stored, len);
    return true;
}

static bool store_save(void *ctx, const void *buf, size_t len)
{
    (void)ctx;
    RW_FUZZ_REQUIRE(len == sizeof(rw_config));
    rw_config *copy = (rw_config *)rw_fuzz_exact_copy(buf, len);
    RW_FUZZ_REQUIRE(rw_config_valid(copy)); /* the core only ever writes a sealed record */
    bool ok = (h.options & OPT_SAVE_FAILS) == 0u;
    if (ok) {
        h.stored = *copy;
        h.stored_present = true;
    }
    free(copy);
    return ok;
}

static const rw_hal_esc_output ESC = { NULL, esc_write, NULL };
static const rw_hal_encoder ENCODER = { NULL, encoder_read };
static const rw_hal_battery BATTERY = { NULL, battery_read };
static const rw_hal_scheduler SCHEDULER = { NULL, overruns };
static const rw_hal_spindle SPINDLE = { NULL, spindle_read, spindle_write };
/* A PROVISION_COMMIT's write, done at once (a RAM store): the same checks and failure option as save. */
static uint8_t store_status;
static bool store_request_save(void *ctx, const void *buf, size_t len)
{
    store_status = store_save(ctx, buf, len) ? RW_CONFIG_SAVE_DONE : RW_CONFIG_SAVE_FAILED;
    return true;
}

static uint8_t store_save_status(void *ctx)
{
    (void)ctx;
    return store_status;
}

static const rw_hal_config_store STORE = { NULL, store_load, store_save, store_request_save, store_save_status };
static rw_hal_link SERIAL_LINK = { &h.serial, link_recv, link_reply, link_accept, link_send };
static rw_hal_link WIFI_LINK = { &h.wifi, link_recv, link_reply, link_accept, link_send };

/* ---- the run ------------------------------------------------------------------------------------------ */

static void push(fake_link *l, const uint8_t *bytes, size_t n, bool replay)
{
    if (l->count >= QUEUE_DEPTH) {
        return; /* the link's buffer is full: dropped, as a real UDP socket would */
    }
    unsigned slot = (l->head + l->count) % QUEUE_DEPTH;
    memcpy(l->queue[slot], bytes, n);
    l->queue_len[slot] = n;
    l->queue_replay[slot] = replay;
    ++l->count;
}

static void check_wifi_auth(const fake_link *l)
{
    if (!l->delivered) {
        return;
    }
    rw_frame f;
    if (rw_frame_decode(l->delivered_bytes, l->delivered_len, &f) != RW_DECODE_OK) {
        RW_FUZZ_REQUIRE(l->accepts == 0u); /* a malformed frame never becomes the peer */
        return;
    }
    if (rw_msg_info_find(f.msg_id)->kind == RW_MSG_KIND_HELLO) {
        RW_FUZZ_REQUIRE(l->accepts == 0u);
        return;
    }
    const rw_config *c = &h.core.state.config;
    bool authentic = c->key_set != 0u && (f.flags & RW_FRAME_FLAG_SIGNED) != 0u && rw_frame_tag_valid(&f, c->key) &&
                     f.session_id == rw_core_session_id(&h.core);
    if (!authentic || l->delivered_replay) {
        RW_FUZZ_REQUIRE(l->replies == 0u && l->accepts == 0u);
    }
}

static void check_params(void)
{
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        RW_FUZZ_REQUIRE(rw_params_check(&h.core.params, (uint8_t)i, h.core.params.value[i], true) == RW_DECODE_OK);
    }
}

static void tick(const rw_hal *hal)
{
    fake_link *links[2] = { &h.serial, &h.wifi };
    for (unsigned i = 0u; i < 2u; ++i) {
        links[i]->delivered = false;
        links[i]->replies = links[i]->sends = links[i]->accepts = 0u;
    }
    /* the plant advances to this tick: encoder edges from the rope speed */
    h.now_us += h.tick_us;
    if (!h.encoder_silent) {
        float r = h.core.params.value[RW_PARAM_WHEEL_RADIUS_M];
        float cpr = h.core.params.value[RW_PARAM_ENCODER_COUNTS_PER_REV];
        h.count_acc += h.rope_mps * (double)h.tick_us * 1e-6 * (double)cpr / (2.0 * 3.14159265358979 * (double)r);
        if (h.count_acc >= 1.0) {
            uint32_t whole = h.count_acc > 1e6 ? 1000000u : (uint32_t)h.count_acc;
            h.counts += whole;
            h.count_acc -= whole;
            if (h.count_acc > 1.0) {
                h.count_acc = 0.0;
            }
            h.last_edge_us = h.now_us - 7u;
        }
    }
    double raw = (double)(h.spindle_raw_speed & 1023u) / 128.0;
    h.spindle_pos += (h.spindle_raw_speed & 1024u) != 0u ? -raw : raw;

    bool first = !h.core.state.started;
    rw_core_tick(&h.core, hal, h.now_us);
    ++h.ticks;

    if (first) {
        if (!h.record_was_valid) {
            for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
                RW_FUZZ_REQUIRE(h.core.params.value[i] == rw_param_table[i].default_value ||
                                h.serial.delivered || h.wifi.delivered);
            }
            RW_FUZZ_REQUIRE(rw_core_session_id(&h.core) == 1u || h.serial.delivered); /* or a commit came */
        } else {
            /* session = epoch + boot counter + 1; a used-up counter stays and the key is forgotten */
            bool used_up = h.record_boot_counter == RW_CONFIG_BOOT_COUNTER_MAX;
            RW_FUZZ_REQUIRE(rw_core_session_id(&h.core) ==
                                h.record_session_epoch + h.record_boot_counter + (used_up ? 0u : 1u) ||
                            h.serial.delivered); /* or a commit came in the first tick */
            RW_FUZZ_REQUIRE(!used_up || h.core.state.config.key_set == 0u || h.serial.delivered);
        }
    }
    RW_FUZZ_REQUIRE(h.core.state.state < RW_STATE_COUNT);
    check_params();
    unsigned replies = h.serial.replies + h.wifi.replies;
    unsigned sends = h.serial.sends + h.wifi.sends;
    RW_FUZZ_REQUIRE(h.serial.replies <= 1u && h.wifi.replies <= 1u && sends <= 1u);
    RW_FUZZ_REQUIRE(replies == 0u || sends == 0u);
    check_wifi_auth(&h.wifi);
    RW_FUZZ_AFTER_TICK();
}

static void sensor_event(const uint8_t *b, size_t n)
{
    if (n >= 2u) {
        h.battery_mv = (uint16_t)(b[0] | (b[1] << 8));
    }
    if (n >= 3u) {
        h.encoder_silent = (b[2] & 1u) != 0u;
    }
    if (n >= 4u) {
        h.spindle_silent = (b[3] & 1u) != 0u;
    }
    if (n >= 6u) {
        h.spindle_load_raw = (uint16_t)((b[4] | (b[5] << 8)) & 2047u);
    }
    if (n >= 7u) {
        h.limit_switch = (b[6] & 1u) != 0u;
    }
    if (n >= 9u) {
        uint16_t period = (uint16_t)(b[7] | (b[8] << 8));
        h.tick_us = period == 0u ? 1000u : period;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    memset(&h, 0, sizeof h);
    store_status = RW_CONFIG_SAVE_IDLE;
    h.serial.id = RW_LINK_SERIAL;
    h.wifi.id = RW_LINK_WIFI;
    h.now_us = START_US;
    h.tick_us = 1000u;
    h.battery_mv = 12000u;
    size_t at = 0u;
    h.options = size > 0u ? data[at++] : 0u;

    /* the stored record: from the input, or a valid one holding the test key */
    if ((h.options & OPT_FUZZ_RECORD) != 0u) {
        size_t n = size - at < sizeof h.stored ? size - at : sizeof h.stored;
        memcpy(&h.stored, data + at, n);
        at += n;
        if ((h.options & OPT_SEAL_RECORD) != 0u) {
            h.stored.magic = RW_CONFIG_MAGIC;
            h.stored.version = (uint16_t)RW_CONFIG_VERSION;
            h.stored.size = (uint16_t)sizeof h.stored;
            rw_config_seal(&h.stored);
        }
    } else {
        rw_config_defaults(&h.stored);
        rw_config_set_key(&h.stored, TEST_KEY);
        h.stored.boot_counter = 41u;
        rw_config_seal(&h.stored);
    }
    h.stored_present = true;
    bool has_store = (h.options & OPT_NO_STORE) == 0u;
    h.record_was_valid = has_store && rw_config_valid(&h.stored);
    h.record_boot_counter = h.stored.boot_counter;
    h.record_session_epoch = h.stored.session_epoch;

    rw_hal hal = {
        .esc = &ESC,
        .encoder = &ENCODER,
        .battery = &BATTERY,
        .link = &WIFI_LINK,
        .scheduler = &SCHEDULER,
        .spindle = (h.options & OPT_NO_SPINDLE) != 0u ? NULL : &SPINDLE,
        .serial = &SERIAL_LINK,
        .config = has_store ? &STORE : NULL,
    };
    rw_core_init(&h.core);
    RW_FUZZ_REQUIRE(h.core.state.pulse_us == 1000u);

    if ((h.options & OPT_PREROLL) != 0u) {
        for (unsigned i = 0u; i < 600u; ++i) {
            tick(&hal);
        }
    }
    while (at + 2u <= size && h.ticks < MAX_TICKS) {
        uint8_t tag = data[at];
        size_t len = data[at + 1u];
        at += 2u;
        if (len > size - at) {
            len = size - at;
        }
        const uint8_t *bytes = data + at;
        at += len;
        switch (tag & 3u) {
        case 0u:
            push(&h.serial, bytes, len, false);
            break;
        case 1u:
            push(&h.wifi, bytes, len, false);
            break;
        case 2u:
            sensor_event(bytes, len);
            break;
        default:
            if (len > 0u && h.last_signed_len > 0u) {
                push(&h.wifi, h.last_signed, h.last_signed_len, true);
            }
            break;
        }
        unsigned v = tag >> 2;
        unsigned ticks = v < 32u ? v : (v - 31u) * 32u;
        for (unsigned i = 0u; i < ticks && h.ticks < MAX_TICKS; ++i) {
            tick(&hal);
        }
    }
    /* drain what is still queued */
    for (unsigned i = 0u; i < 2u * QUEUE_DEPTH + 2u; ++i) {
        tick(&hal);
    }
    return 0;
}
