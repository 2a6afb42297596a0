/* The firmware core: rope speed loop, ToV guard, state machine, command handling and telemetry.
 *
 * Portable C: no Arduino header, no clock reads, no heap. The caller owns an rw_core, calls rw_core_init
 * once, then rw_core_tick once per control period with the HAL (by reference) and the tick time. Every
 * output goes through the HAL: the ESC pulse, replies, events and telemetry (at most one datagram
 * received per link and one sent per tick).
 *
 * Link security: over WiFi every frame but HELLO must be signed (SipHash-2-4 with the provisioned key) for
 * the current session (session epoch + boot counter, kept in the configuration record) with a counter above
 * the last accepted one; anything else is dropped and counted (rx_auth_failed, rx_replayed). Without a key
 * nothing is accepted over WiFi. USB serial is trusted: unsigned frames and the PROVISION_* messages.
 *
 * Tick (period = the time between calls, 1 ms on the board and in SIL):
 *   1. encoder (every tick, for the silence check) -> M/T estimator -> rope speed (m/s), on speed ticks;
 *      battery (V)
 *   2. one received datagram -> decode -> duplicate check -> command -> ACK/NACK (straight to its sender)
 *   3. supervision (every tick): arming hold, heartbeat loss -> SPINDOWN, encoder silence -> FAULT, loop
 *      collapse, battery cutoff -> SPINDOWN, spindle outcomes (homed, secured, stall, no answer) -> grasp states
 *      (and, on speed ticks after the PI step, the load-loss monitor: load vanished -> SPINDOWN)
 *   4. control: target -> ramp -> PI + feed-forward -> ESC pulse (never under esc_min_us), on speed ticks;
 *      a state that stops driving the rope (ESTOP, FAULT, ARMED, ...) sets the minimum pulse in the same tick
 *   5. telemetry at telemetry_rate_hz; one queued frame to the peer (over a keyed WiFi link: signed over idle
 *      ticks first, see below)
 *   6. a parameter change staged by PARAM_SET: one module converted, on a tick that took no datagram
 *      (rw_core_params.c), so its new values are in force from the next tick on, whole
 *   burst (BURST_START, rw_burst.h): while capturing, every tick stores its sample (encoder, the pulse it wrote,
 *      battery) after step 4; once captured, an idle tick with an empty outbox and nothing being signed packs
 *      one BURST_DATA frame instead of signing (its pack costs what a telemetry pack does)
 *
 * Schedule: the calls alternate between two kinds of tick, so that the expensive periodic jobs never
 * share a tick (the worst-case tick is one job plus the per-tick work, not their sum; on the M0+ every
 * float operation is a libgcc call):
 *   speed tick (odd calls):    M/T estimator + ramp + PI + feed-forward, dt = the time since the last
 *                              speed tick (2 ms at a 1 ms tick: 500 Hz, above the ESC's 400 Hz frame rate)
 *   other tick (even calls):   the telemetry pack when due; otherwise the spindle loop and the load-loss
 *                              check when due (RW_CORE_SPINDLE_PERIOD_MS); either waits for the next tick
 *                              of its kind;
 *                              with neither, the feed-forward's battery factor (60 / (2 pi r kv V), one
 *                              division) is refreshed if the battery reading changed, so the speed tick
 *                              never divides for it (the feed-forward sees the battery a few ms late);
 *                              and an idle other tick (neither job) advances the signing of the next queued
 *                              frame (rw_signer.h): begin + a few MAC blocks, or the last blocks + finish +
 *                              send, RW_CORE_MAC_TICK_BUDGET blocks' worth a tick, so a telemetry frame leaves
 *                              two idle ticks (about 4-8 ms) after it was packed and no tick carries a whole
 *                              MAC. A received command is still verified, executed and ACKed (signed in one
 *                              piece) in the tick it arrives: that tick is the one over the periodic budget.
 * A telemetry frame held back by the schedule (at most 2 ms) does not shift the next one: the period
 * counts from when it was due. A spindle step held back measures its real elapsed time as always. The
 * first call is an "other" tick, so the first telemetry frame leaves at uptime 0.
 */
#ifndef RW_CORE_H
#define RW_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rw_burst.h"
#include "rw_config.h"
#include "rw_duplicate_cache.h"
#include "rw_hal.h"
#include "rw_load_monitor.h"
#include "rw_outbox.h"
#include "rw_params.h"
#include "rw_protocol.h"
#include "rw_signer.h"
#include "rw_speed_loop.h"
#include "rw_spindle.h"
#include "rw_tov_guard.h"

/* The tick period the controllers are prepared for (rw_core_apply_params), microseconds: the board's and the
 * SIL's. Any other period works the same, at the cost of converting gains for it on the tick. */
#define RW_CORE_TICK_US 1000u
/* Under this measured speed the rope counts as stopped (spin-down done, DISARM allowed). */
#define RW_CORE_STOPPED_MPS 0.15f
/* Throttle above idle, for the encoder-silence check: the ESC pulse is more than this over esc_min_us. */
#define RW_CORE_THROTTLE_ACTIVE_US 30u
/* The spindle loop runs every this many milliseconds (one AX-12A read and one write each time); the spec owns it
 * (a host waiting on MOVING needs it). */
#define RW_CORE_SPINDLE_PERIOD_MS RW_SPINDLE_PERIOD_MS
/* A telemetry frame this late at most (ms) was held back by the schedule, not by a stalled loop. */
#define RW_CORE_SCHEDULE_MAX_HOLD_MS 2u
/* Signing over idle ticks (rw_signer.h), in units of one MAC block (8 bytes, two SipRounds, ~250 Cortex-M0+
 * cycles): the work an idle tick may do, what beginning a frame costs (copy and checksum of up to 73 bytes)
 * and what finishing it costs (the last two blocks, four finalization rounds, the send). A full 64-byte
 * payload (TELEMETRY, BURST_DATA: 73 bytes + session id = 9 fixed blocks) is then signed and sent in two idle
 * ticks: begin + 4 blocks, then 5 blocks + finish; each under 10 % of a 1 kHz tick on the M0+
 * (bench/bench_tick_instructions.py). */
#define RW_CORE_MAC_TICK_BUDGET 9u
#define RW_CORE_MAC_BEGIN_COST 5u
#define RW_CORE_MAC_FINISH_COST 4u
/* An idle tick that also refreshes the feed-forward's battery factor (one float division, ~500 cycles) signs
 * this much less. */
#define RW_CORE_MAC_BATTERY_COST 2u

typedef struct rw_core_counters {
    uint16_t rx_ok;
    uint16_t rx_bad;
    uint16_t rx_duplicates;
    uint16_t nacks;
    uint16_t events;
    uint16_t rx_auth_failed;
    uint16_t rx_replayed;
} rw_core_counters;

/* Which link a frame came in on / the peer is on. WiFi frames must be signed; USB serial is trusted. */
typedef enum {
    RW_LINK_NONE = 0,
    RW_LINK_WIFI = 1,
    RW_LINK_SERIAL = 2,
} rw_link_id;

typedef struct rw_core {
    rw_params params; /* public: read through rw_params_get; set through PARAM_SET or rw_core_set_param */
    uint32_t reset_cause; /* public: the board's reset reason, set before the first tick (BOOT event arg) */
    struct {
        rw_speed_loop loop;       /* the rope speed loop: estimator, ramp, PI, throttle map (rw_speed_loop.h) */
        rw_tov_guard guard;       /* airborne setpoints and loop collapse (supervisor) */
        rw_spindle spindle;
        rw_load_monitor load_monitor; /* load loss of the flying rope (rw_core_load_loss.c) */
        rw_duplicate_cache duplicates;
        rw_outbox outbox;
        rw_signer signer;         /* the outbox frame being signed for the WiFi peer (over idle ticks) */
        rw_core_counters counters;
        rw_config config;         /* the stored record (RAM copy): key, WiFi, boot counter; staged changes */
        bool config_dirty;        /* provisioning changed it since the last PROVISION_COMMIT */
        bool commit_pending;      /* a PROVISION_COMMIT's record is being written outside the tick; answered when done */
        uint8_t commit_link;      /* rw_link_id, msg_id, seq and checksum of that command (its answer, the duplicate cache) */
        uint8_t commit_msg_id;
        uint16_t commit_seq;
        uint16_t commit_checksum;
        rw_config commit_record;  /* the record being written: the RAM record once the store says it is written */
        bool key_staged;          /* PROVISION_SET_KEY received; active from the next commit */
        uint8_t staged_key[RW_KEY_LEN];
        uint32_t session_id;      /* this session: epoch + boot counter at boot, a new epoch at PROVISION_COMMIT */
        uint64_t host_counter;    /* last accepted signed-frame counter of this session */
        uint64_t tx_counter;      /* counter of the device's own signed frames */
        uint8_t peer_link;        /* rw_link_id of the host telemetry and events go to */

        uint8_t state;            /* rw_state */
        uint8_t spindown_cause;   /* rw_cause of the current SPINDOWN */
        uint16_t fault_bits;      /* rw_fault */
        bool started;             /* first tick seen */
        bool arming_hold_done;
        bool heartbeat_lost;      /* reported once per silence */
        uint32_t last_now_us;
        uint32_t uptime_ms;
        uint32_t uptime_rem_us;   /* sub-millisecond remainder of uptime */
        uint32_t last_host_frame_ms;
        uint32_t encoder_silent_ms;
        uint32_t telemetry_due_ms;
        uint32_t spindle_due_ms;
        uint32_t spindle_last_ms;
        uint32_t battery_low_ms;
        bool grasp_pending;       /* GRASP: RELAX goes on to RETRACT once the rope has stopped */
        bool speed_tick_next;     /* schedule: the next call is a speed tick (see the schedule above) */
        uint32_t speed_dt_us;     /* time since the last speed tick, microseconds */
        uint32_t telemetry_period_ms; /* round(1000 / telemetry_rate_hz) (rw_core_apply_params) */
        uint16_t tx_seq[2];       /* next seq per link: [0] WiFi, [1] USB serial (rw_core_take_seq) */
        uint16_t last_cmd_seq;
        uint16_t params_pending;  /* RW_PARAM_MODULE_* bits changed by PARAM_SET, not yet prepared (rw_core_params.c) */
        uint8_t params_pending_ticks; /* ticks with a datagram the lowest pending module has waited */
        bool took_datagram;       /* this tick received a datagram on a link (cleared at the tick's end) */

        float target_mps;         /* commanded rope speed */
        float measured_mps;
        float battery_v;
        uint16_t battery_mv;
        uint16_t pulse_us;
        uint16_t pulse_third_us;  /* the same pulse in thirds of a microsecond (what a TCC1 HAL outputs) */
        uint32_t encoder_counts;  /* edges since the first tick (TELEMETRY, burst samples) */
        uint32_t encoder_edge_us; /* the latest edge's time on the uptime clock, us (wraps) */
        uint32_t encoder_boot_counts; /* the HAL's count at the first tick */
        bool encoder_origin_set;
        rw_burst burst;           /* burst capture (BURST_START, rw_burst.h): last, it is the big one */
    } state;
} rw_core;

#ifdef __cplusplus
extern "C" {
#endif

void rw_core_init(rw_core *core);

/* One control tick at time now_us (the tick clock, wraps). The first call latches the clock and loads the
 * configuration record through hal->config: a valid stored record's parameters replace those set before
 * (rw_core_set_param), its key becomes the link key, and its boot counter goes up by one (the session:
 * session epoch + boot counter). */
void rw_core_tick(rw_core *core, const rw_hal *hal, uint32_t now_us);

/* Set a parameter as PARAM_SET would (same checks); returns RW_DECODE_OK or the NACK reason. The value is
 * stored at once (rw_params_get, PARAM_VALUE, the commands' checks see it); the controllers it feeds are
 * converted at the end of a later tick, one module a tick (rw_core_params.c), or by the first tick's load of
 * the stored record, or rw_core_params_settle_all. */
int rw_core_set_param(rw_core *core, uint8_t param_id, float value);

/* Convert every staged parameter change now (for bindings and tests; the tick does it by itself). */
void rw_core_params_settle_all(rw_core *core);

/* The RW_PARAM_MODULE_* bits of staged changes not yet converted (0: the controllers hold every value). */
uint16_t rw_core_params_pending(const rw_core *core);

/* True when nothing waits to be sent: the outbox is empty and no frame is being signed. */
bool rw_core_tx_idle(const rw_core *core);

/* sizeof(rw_core), for bindings that allocate the core themselves (the pytest suites use ctypes). */
size_t rw_core_sizeof(void);

/* The current session id (valid from the first tick; a PROVISION_COMMIT starts a new one). */
static inline uint32_t rw_core_session_id(const rw_core *core)
{
    return core->state.session_id;
}

static inline uint8_t rw_core_state(const rw_core *core)
{
    return core->state.state;
}

#ifdef __cplusplus
}
#endif

#endif /* RW_CORE_H */
