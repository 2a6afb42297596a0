/* Shared by the fuzz targets: the message table (id -> unpack/encode through a generic view) and the
 * invariant check. Fuzz targets only, never linked into firmware. */
#ifndef RW_FUZZ_COMMON_H
#define RW_FUZZ_COMMON_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "rw_protocol.h"

/* An invariant that must hold on every input: a violation aborts the run (libFuzzer saves the input). */
#define RW_FUZZ_REQUIRE(cond) \
    do {                      \
        if (!(cond)) {        \
            __builtin_trap(); \
        }                     \
    } while (0)

/* A heap copy of exactly n bytes (n == 0: a 1-byte allocation that is never read), so that AddressSanitizer
 * reports any read past the end. */
static inline uint8_t *rw_fuzz_exact_copy(const uint8_t *data, size_t n)
{
    uint8_t *p = malloc(n == 0u ? 1u : n);
    RW_FUZZ_REQUIRE(p != NULL);
    if (n != 0u) {
        memcpy(p, data, n);
    }
    return p;
}

/* X(lower, UPPER) for every message of the schema. */
#define RW_FUZZ_MESSAGES(X)                                                                                   \
    X(heartbeat, HEARTBEAT) X(ack, ACK) X(nack, NACK) X(telemetry, TELEMETRY) X(event, EVENT)                 \
    X(param_value, PARAM_VALUE) X(session_info, SESSION_INFO) X(provision_status, PROVISION_STATUS)           \
    X(arm, ARM) X(disarm, DISARM) X(set_rope_speed, SET_ROPE_SPEED) X(spindown, SPINDOWN) X(estop, ESTOP)     \
    X(param_get, PARAM_GET) X(param_set, PARAM_SET) X(set_loop, SET_LOOP) X(relax, RELAX)                     \
    X(retract, RETRACT) X(grasp, GRASP) X(release, RELEASE) X(home, HOME) X(hello, HELLO)                     \
    X(provision_set_key, PROVISION_SET_KEY) X(provision_set_wifi_ssid, PROVISION_SET_WIFI_SSID)               \
    X(provision_set_wifi_password, PROVISION_SET_WIFI_PASSWORD) X(provision_commit, PROVISION_COMMIT)        \
    X(provision_get, PROVISION_GET) X(sil_sensors, SIL_SENSORS) X(sil_actuators, SIL_ACTUATORS)             \
    X(burst_start, BURST_START) X(burst_data, BURST_DATA)

/* Unpack payload (exactly the message's payload length) into its struct, re-encode it with seq into out
 * (out_cap bytes); returns the encoded frame length (0: unknown id). */
static inline size_t rw_fuzz_unpack_encode(uint8_t msg_id, const uint8_t *payload, uint16_t seq, uint8_t *out,
                                           size_t out_cap)
{
    switch (msg_id) {
#define RW_FUZZ_CASE(lower, UPPER)                                   \
    case RW_MSG_ID_##UPPER: {                                        \
        rw_msg_##lower msg;                                          \
        memset(&msg, 0xA5, sizeof msg);                              \
        rw_msg_##lower##_unpack(&msg, payload);                      \
        return rw_msg_##lower##_encode(&msg, seq, out, out_cap);     \
    }
        RW_FUZZ_MESSAGES(RW_FUZZ_CASE)
#undef RW_FUZZ_CASE
    default:
        return 0u;
    }
}

/* Messages whose payload is text (char[N], NUL-terminated on unpack: the re-encoded payload may differ). */
static inline int rw_fuzz_has_text(uint8_t msg_id)
{
    return msg_id == RW_MSG_ID_PROVISION_SET_WIFI_SSID || msg_id == RW_MSG_ID_PROVISION_SET_WIFI_PASSWORD ||
           msg_id == RW_MSG_ID_PROVISION_STATUS;
}

#endif /* RW_FUZZ_COMMON_H */
