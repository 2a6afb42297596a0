/*
 * Unity tests of the firmware core top level (rw_core): state transitions and their STATE_CHANGED
 * events, the arming hold, ESTOP, NACK reasons (frame and command level), retransmissions, outbox
 * priority, one datagram in and out per tick, heartbeat loss, encoder silence, tick-clock wrap, and the
 * signed link (unsigned, forged, replayed, foreign-session frames dropped and counted; replies signed).
 *
 * A fake HAL in C: the encoder is a wheel at a set rope speed (edge times in integer nanoseconds,
 * 64 edges/rev, 15 mm wheel), the battery reads a set voltage, the link (WiFi) delivers queued datagrams
 * and records every reply and sent frame, and the config store is a fresh flash record provisioned with
 * the test key (bytes 0..15, never a real one), so the first boot is session 1. The host side signs its
 * frames with rw_frame_sign (generated codec) for that session with a growing counter; malformed frames
 * are queued as they are (the core NACKs them before any authentication). One tick = 1 ms.
 * Run with `pio test -e native`.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_core.h"

#define TICK_US 1000u
#define MAX_OUT 4096u
#define MAX_IN 8u
#define TWO_PI 6.283185307179586

/* ---- fake HAL ------------------------------------------------------------------------------------ */

typedef struct {
    uint8_t bytes[RW_MAX_FRAME_LEN];
    uint8_t len;
    bool reply; /* true: reply() to the sender, false: send() to the peer */
    uint32_t tick;
} out_frame;

static struct {
    /* inputs */
    uint64_t t_ns;
    uint32_t clock_offset_us;
    uint32_t counts;
    uint32_t last_edge_us;
    uint64_t period_ns; /* 0: wheel stopped */
    uint64_t next_edge_ns;
    uint16_t battery_mv;
    uint8_t inbox[MAX_IN][128];
    size_t inbox_len[MAX_IN];
    unsigned in_head;
    unsigned in_count;
    /* outputs */
    uint16_t pulse_us;
    uint32_t ticks;
    out_frame out[MAX_OUT];
    unsigned n_out;
    unsigned accept_peer_calls;
    unsigned out_this_tick_max;
    unsigned out_this_tick;
} fake;

static rw_core core;
static uint16_t host_seq;
static uint64_t host_counter; /* counter of the last frame the host signed */
static rw_config flash;       /* the fake config store's record */
static unsigned flash_saves;
static const uint8_t test_key[RW_KEY_LEN] = { 0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u };

static rw_encoder_sample encoder_read(void *ctx)
{
    (void)ctx;
    rw_encoder_sample s = { fake.counts, fake.last_edge_us };
    return s;
}

static uint16_t battery_read_mv(void *ctx)
{
    (void)ctx;
    return fake.battery_mv;
}

static void esc_write_pulse_us(void *ctx, uint16_t pulse_us)
{
    (void)ctx;
    fake.pulse_us = pulse_us;
}

static size_t link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    (void)ctx;
    if (fake.in_count == 0u) {
        return 0u;
    }
    unsigned i = fake.in_head;
    fake.in_head = (fake.in_head + 1u) % MAX_IN;
    --fake.in_count;
    size_t n = fake.inbox_len[i];
    memcpy(buf, fake.inbox[i], n < cap ? n : cap);
    return n <= cap ? n : cap + 1u;
}

static void record(const uint8_t *frame, size_t len, bool reply)
{
    TEST_ASSERT_TRUE_MESSAGE(len > 0u && len <= RW_MAX_FRAME_LEN, "the core emits whole frames");
    TEST_ASSERT_TRUE(fake.n_out < MAX_OUT);
    out_frame *o = &fake.out[fake.n_out++];
    memcpy(o->bytes, frame, len);
    o->len = (uint8_t)len;
    o->reply = reply;
    o->tick = fake.ticks;
    ++fake.out_this_tick;
}

static void link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    (void)ctx;
    record(frame, len, true);
}

static void link_send(void *ctx, const uint8_t *frame, size_t len)
{
    (void)ctx;
    record(frame, len, false);
}

static void link_accept_peer(void *ctx)
{
    (void)ctx;
    ++fake.accept_peer_calls;
}

static uint32_t tick_overruns(void *ctx)
{
    (void)ctx;
    return 0u;
}

static bool config_load(void *ctx, void *buf, size_t len)
{
    (void)ctx;
    TEST_ASSERT_EQUAL_UINT(sizeof flash, len);
    memcpy(buf, &flash, len);
    return true;
}

static bool config_save(void *ctx, const void *buf, size_t len)
{
    (void)ctx;
    TEST_ASSERT_EQUAL_UINT(sizeof flash, len);
    memcpy(&flash, buf, len);
    ++flash_saves;
    return true;
}

/* A PROVISION_COMMIT's write: at once (flash_hold == false), or held BUSY until the test lets it finish. */
static bool flash_hold;
static bool flash_fail;
static uint8_t flash_status;
static rw_config flash_pending;

static bool config_request_save(void *ctx, const void *buf, size_t len)
{
    if (flash_status == RW_CONFIG_SAVE_BUSY) {
        return false;
    }
    TEST_ASSERT_EQUAL_UINT(sizeof flash_pending, len);
    memcpy(&flash_pending, buf, len);
    flash_status = RW_CONFIG_SAVE_BUSY;
    if (!flash_hold) {
        flash_status = !flash_fail && config_save(ctx, &flash_pending, len) ? RW_CONFIG_SAVE_DONE : RW_CONFIG_SAVE_FAILED;
    }
    return true;
}

static uint8_t config_save_status(void *ctx)
{
    (void)ctx;
    return flash_status;
}

/* The held write finishes (the board's background loop wrote the flash). */
static void flash_release(void)
{
    flash_hold = false;
    flash_status = !flash_fail && config_save(NULL, &flash_pending, sizeof flash_pending) ? RW_CONFIG_SAVE_DONE
                                                                                         : RW_CONFIG_SAVE_FAILED;
}

static const rw_hal_config_store hal_config = { NULL, config_load, config_save, config_request_save,
                                                config_save_status };
static const rw_hal_esc_output hal_esc = { NULL, esc_write_pulse_us, NULL };
static const rw_hal_encoder hal_encoder = { NULL, encoder_read };
static const rw_hal_battery hal_battery = { NULL, battery_read_mv };
static const rw_hal_link hal_link = { NULL, link_recv, link_reply, link_accept_peer, link_send };
static const rw_hal_scheduler hal_scheduler = { NULL, tick_overruns };
/* A spindle that answers but never moves (enough for the refusals): position register fixed. */
static struct {
    unsigned writes;
    uint16_t last_raw;
} spindle_fake;

static bool spindle_read(void *ctx, rw_spindle_reading *out)
{
    (void)ctx;
    out->position_raw = 512u;
    out->speed_raw = 0u;
    out->load_raw = 0u;
    out->limit_switch = false;
    return true;
}

static void spindle_write_moving_speed_raw(void *ctx, uint16_t raw)
{
    (void)ctx;
    ++spindle_fake.writes;
    spindle_fake.last_raw = raw;
}

static const rw_hal_spindle hal_spindle_fake = { NULL, spindle_read, spindle_write_moving_speed_raw };

/* Designated: interfaces a HAL does not set stay NULL = not fitted. */
static const rw_hal hal_no_spindle = {
    .esc = &hal_esc, .encoder = &hal_encoder, .battery = &hal_battery, .link = &hal_link, .scheduler = &hal_scheduler,
    .config = &hal_config,
};
static const rw_hal hal_with_spindle = {
    .esc = &hal_esc, .encoder = &hal_encoder, .battery = &hal_battery, .link = &hal_link, .scheduler = &hal_scheduler,
    .spindle = &hal_spindle_fake, .config = &hal_config,
};
/* USB serial (trusted, provisioning): one datagram waiting at most; answers recorded with their kind. */
static struct {
    uint8_t in[128];
    size_t in_len;
    unsigned replies;
    uint8_t last_msg_id;   /* of the last answer: ACK or NACK */
    uint8_t last_cmd_msg_id;
    uint8_t last_reason;   /* 0 for an ACK */
    int32_t last_detail;
} serial_fake;

static size_t serial_recv(void *ctx, uint8_t *buf, size_t cap)
{
    (void)ctx;
    size_t n = serial_fake.in_len;
    if (n == 0u || n > cap) {
        return 0u;
    }
    memcpy(buf, serial_fake.in, n);
    serial_fake.in_len = 0u;
    return n;
}

static void serial_out(void *ctx, const uint8_t *frame, size_t len)
{
    (void)ctx;
    rw_frame f;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(frame, len, &f));
    if (f.msg_id == RW_MSG_ID_ACK) {
        rw_msg_ack a;
        rw_msg_ack_unpack(&a, f.payload);
        serial_fake.last_cmd_msg_id = a.cmd_msg_id;
        serial_fake.last_reason = 0u;
    } else if (f.msg_id == RW_MSG_ID_NACK) {
        rw_msg_nack n;
        rw_msg_nack_unpack(&n, f.payload);
        serial_fake.last_cmd_msg_id = n.cmd_msg_id;
        serial_fake.last_reason = n.reason;
        serial_fake.last_detail = n.detail;
    } else {
        return;
    }
    serial_fake.last_msg_id = f.msg_id;
    ++serial_fake.replies;
}

static void serial_accept(void *ctx)
{
    (void)ctx;
}

static const rw_hal_link hal_serial = { NULL, serial_recv, serial_out, serial_accept, serial_out };
static const rw_hal hal_with_serial = {
    .esc = &hal_esc, .encoder = &hal_encoder, .battery = &hal_battery, .link = &hal_link, .scheduler = &hal_scheduler,
    .serial = &hal_serial, .config = &hal_config,
};
static const rw_hal *hal = &hal_no_spindle;

/* ---- driving the core ---------------------------------------------------------------------------- */

static void set_rope_speed_mps(double v_mps)
{
    if (v_mps <= 0.0) {
        fake.period_ns = 0u;
        return;
    }
    double counts_per_s = v_mps / (TWO_PI * 0.015) * 64.0;
    bool was_stopped = fake.period_ns == 0u;
    fake.period_ns = (uint64_t)(1.0e9 / counts_per_s + 0.5);
    /* A faster wheel brings the next edge forward (one period from now at the latest). */
    if (was_stopped || fake.next_edge_ns > fake.t_ns + fake.period_ns) {
        fake.next_edge_ns = fake.t_ns + fake.period_ns;
    }
}

static void tick(void)
{
    if (fake.ticks > 0u) {
        fake.t_ns += (uint64_t)TICK_US * 1000u;
    }
    while (fake.period_ns != 0u && fake.next_edge_ns <= fake.t_ns) {
        ++fake.counts;
        fake.last_edge_us = (uint32_t)(fake.clock_offset_us + (uint32_t)(fake.next_edge_ns / 1000u));
        fake.next_edge_ns += fake.period_ns;
    }
    fake.out_this_tick = 0u;
    rw_core_tick(&core, hal, (uint32_t)(fake.clock_offset_us + (uint32_t)(fake.t_ns / 1000u)));
    if (fake.out_this_tick > fake.out_this_tick_max) {
        fake.out_this_tick_max = fake.out_this_tick;
    }
    ++fake.ticks;
}

static uint32_t now_ms(void)
{
    return (uint32_t)(fake.t_ns / 1000000u);
}

static void run_ms(uint32_t ms)
{
    for (uint32_t i = 0u; i < ms; ++i) {
        tick();
    }
}

/* Ticks until every queued frame has gone out (frames are signed over idle ticks, so they leave a few ticks
 * after they were queued); fails if the queue has not emptied within 200 ms. */
static void drain(void)
{
    for (uint32_t i = 0u; i < 200u && !rw_core_tx_idle(&core); ++i) {
        tick();
    }
    TEST_ASSERT_TRUE_MESSAGE(rw_core_tx_idle(&core), "frames still queued after 200 ms");
}

/* Queues a datagram exactly as given (malformed ones included). */
static void queue_bytes(const uint8_t *data, size_t len)
{
    TEST_ASSERT_TRUE(fake.in_count < MAX_IN && len <= sizeof fake.inbox[0]);
    unsigned i = (fake.in_head + fake.in_count) % MAX_IN;
    memcpy(fake.inbox[i], data, len);
    fake.inbox_len[i] = len;
    ++fake.in_count;
}

/* The session the core's next received frame belongs to: its boot counter (the stored one + 1 before
 * the first tick loads and bumps it). */
static uint32_t host_session_id(void)
{
    return core.state.started ? rw_core_session_id(&core) : flash.boot_counter + 1u;
}

/* Copies an unsigned frame into out and signs it there for the session with the next counter; returns the
 * signed length. A retransmission is the same frame signed again (new counter). */
static size_t sign_frame(uint8_t out[RW_MAX_FRAME_LEN], const uint8_t *frame, size_t len)
{
    TEST_ASSERT_TRUE(len <= RW_MAX_FRAME_LEN);
    memcpy(out, frame, len);
    size_t n = rw_frame_sign(out, len, RW_MAX_FRAME_LEN, host_session_id(), ++host_counter, test_key);
    TEST_ASSERT_TRUE_MESSAGE(n == len + RW_SIGNATURE_LEN, "a well-formed unsigned frame to sign");
    return n;
}

/* Queues an unsigned frame signed (as the host sends every frame on WiFi). */
static void queue_signed(const uint8_t *frame, size_t len)
{
    uint8_t signed_frame[RW_MAX_FRAME_LEN];
    queue_bytes(signed_frame, sign_frame(signed_frame, frame, len));
}

/* Frame builders (the generated encoders); each returns the frame length. */
static size_t frame_arm(uint8_t *buf, uint16_t seq)
{
    rw_msg_arm m = { 0u };
    return rw_msg_arm_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_disarm(uint8_t *buf, uint16_t seq)
{
    rw_msg_disarm m = { 0u };
    return rw_msg_disarm_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_speed(uint8_t *buf, uint16_t seq, int32_t mmps)
{
    rw_msg_set_rope_speed m = { mmps };
    return rw_msg_set_rope_speed_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_spindown(uint8_t *buf, uint16_t seq)
{
    rw_msg_spindown m = { 0u };
    return rw_msg_spindown_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_estop(uint8_t *buf, uint16_t seq)
{
    rw_msg_estop m = { 0u };
    return rw_msg_estop_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_param_set(uint8_t *buf, uint16_t seq, uint8_t id, float value)
{
    rw_msg_param_set m = { id, value };
    return rw_msg_param_set_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static size_t frame_param_get(uint8_t *buf, uint16_t seq, uint8_t id)
{
    rw_msg_param_get m = { id };
    return rw_msg_param_get_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

static void heartbeat(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    rw_msg_heartbeat m = { now_ms() };
    queue_signed(buf, rw_msg_heartbeat_encode(&m, ++host_seq, buf, sizeof buf));
}

/* The verdict the core replied in the last tick. */
typedef struct {
    bool ack;
    uint8_t cmd_msg_id;
    uint16_t cmd_seq;
    uint8_t reason; /* 0 for an ACK */
    uint8_t state;
    int32_t detail;
} verdict;

static verdict last_reply(void)
{
    verdict v = { false, 0u, 0u, 0u, 0u, 0 };
    TEST_ASSERT_TRUE(fake.n_out > 0u);
    const out_frame *o = &fake.out[fake.n_out - 1u];
    TEST_ASSERT_TRUE_MESSAGE(o->reply && o->tick == fake.ticks - 1u, "a reply in the last tick");
    rw_frame f;
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(o->bytes, o->len, &f));
    TEST_ASSERT_TRUE_MESSAGE((f.flags & RW_FRAME_FLAG_SIGNED) != 0u, "replies on WiFi are signed");
    TEST_ASSERT_TRUE_MESSAGE(rw_frame_tag_valid(&f, test_key), "reply tag valid for the key");
    TEST_ASSERT_EQUAL_UINT32(rw_core_session_id(&core), f.session_id);
    if (f.msg_id == RW_MSG_ID_ACK) {
        rw_msg_ack a;
        rw_msg_ack_unpack(&a, f.payload);
        v.ack = true;
        v.cmd_msg_id = a.cmd_msg_id;
        v.cmd_seq = a.cmd_seq;
        v.state = a.state;
    } else {
        TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_NACK, f.msg_id);
        rw_msg_nack n;
        rw_msg_nack_unpack(&n, f.payload);
        v.cmd_msg_id = n.cmd_msg_id;
        v.cmd_seq = n.cmd_seq;
        v.reason = n.reason;
        v.state = n.state;
        v.detail = n.detail;
    }
    return v;
}

/* Queues an unsigned frame signed for the session, runs one tick, returns the verdict. */
static verdict command(const uint8_t *buf, size_t len)
{
    queue_signed(buf, len);
    tick();
    return last_reply();
}

/* Queues the bytes as they are (a malformed frame), runs one tick, returns the verdict. */
static verdict command_raw(const uint8_t *buf, size_t len)
{
    queue_bytes(buf, len);
    tick();
    return last_reply();
}

static uint8_t sent_msg_id(unsigned i, rw_frame *f)
{
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_frame_decode(fake.out[i].bytes, fake.out[i].len, f));
    return f->msg_id;
}

/* Events sent (not replies) from index `from` on, of one kind; copies up to cap of them. */
static unsigned events_of_kind(unsigned from, uint8_t kind, rw_msg_event *events, unsigned cap)
{
    unsigned n = 0u;
    for (unsigned i = from; i < fake.n_out; ++i) {
        rw_frame f;
        if (fake.out[i].reply || sent_msg_id(i, &f) != RW_MSG_ID_EVENT) {
            continue;
        }
        rw_msg_event e;
        rw_msg_event_unpack(&e, f.payload);
        if (e.event == kind) {
            if (n < cap) {
                events[n] = e;
            }
            ++n;
        }
    }
    return n;
}

static void boot_and_arm(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    tick();
    run_ms(501);
    verdict v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_TRUE(v.ack);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ARMED, rw_core_state(&core));
}

/* The rope follows the core's ramped setpoint (a perfect plant) with a heartbeat every 100 ms, until
 * the state is `state` or max_ms pass. */
static void follow_setpoint_until(uint8_t state, uint32_t max_ms)
{
    for (uint32_t i = 0u; i < max_ms && rw_core_state(&core) != state; ++i) {
        set_rope_speed_mps((double)rw_speed_loop_setpoint_mps(&core.state.loop));
        if (now_ms() % 100u == 0u) {
            heartbeat();
        }
        tick();
    }
    TEST_ASSERT_EQUAL_UINT8(state, rw_core_state(&core));
}

static void to_airborne(int32_t mmps)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    boot_and_arm();
    TEST_ASSERT_TRUE(command(buf, frame_speed(buf, ++host_seq, mmps)).ack);
    follow_setpoint_until(RW_STATE_AIRBORNE, 2000u);
}

void setUp(void)
{
    memset(&fake, 0, sizeof fake);
    memset(&spindle_fake, 0, sizeof spindle_fake);
    hal = &hal_no_spindle;
    fake.battery_mv = 14800u;
    host_seq = 0u;
    host_counter = 0u;
    rw_config_defaults(&flash);
    rw_config_set_key(&flash, test_key);
    flash_saves = 0u;
    flash_hold = false;
    flash_fail = false;
    flash_status = RW_CONFIG_SAVE_IDLE;
    memset(&serial_fake, 0, sizeof serial_fake);
    rw_core_init(&core);
}

void tearDown(void) {}

/* ---- tests ---------------------------------------------------------------------------------------- */

static void test_arm_refused_not_ready_during_hold_then_accepted(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    tick();
    run_ms(400);
    verdict v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_FALSE(v.ack);
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_NOT_READY, v.reason);
    TEST_ASSERT_EQUAL_INT32(500, v.detail);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_DISARMED, rw_core_state(&core));
    run_ms(110);
    rw_msg_event done;
    TEST_ASSERT_EQUAL_UINT(1u, events_of_kind(0u, RW_EVENT_KIND_ARMING_HOLD_DONE, &done, 1u));
    TEST_ASSERT_EQUAL_UINT32(500u, done.time_ms);
    v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_TRUE(v.ack);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ARMED, v.state);
}

static void test_full_cycle_transitions_and_causes(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    to_airborne(4000);
    TEST_ASSERT_TRUE(command(buf, frame_spindown(buf, ++host_seq)).ack);
    follow_setpoint_until(RW_STATE_ARMED, 2000u);
    set_rope_speed_mps(0.0);
    run_ms(20);
    TEST_ASSERT_TRUE(command(buf, frame_disarm(buf, ++host_seq)).ack);
    run_ms(30);
    rw_msg_event ev[8];
    TEST_ASSERT_EQUAL_UINT(6u, events_of_kind(0u, RW_EVENT_KIND_STATE_CHANGED, ev, 8u));
    const uint8_t expect[6][3] = {
        { RW_STATE_DISARMED, RW_STATE_ARMED, RW_CAUSE_COMMAND },
        { RW_STATE_ARMED, RW_STATE_SPINUP, RW_CAUSE_COMMAND },
        { RW_STATE_SPINUP, RW_STATE_AIRBORNE, RW_CAUSE_SPEED_REACHED },
        { RW_STATE_AIRBORNE, RW_STATE_SPINDOWN, RW_CAUSE_COMMAND },
        { RW_STATE_SPINDOWN, RW_STATE_ARMED, RW_CAUSE_SPEED_REACHED },
        { RW_STATE_ARMED, RW_STATE_DISARMED, RW_CAUSE_COMMAND },
    };
    for (unsigned i = 0u; i < 6u; ++i) {
        TEST_ASSERT_EQUAL_UINT8(expect[i][0], ev[i].state_from);
        TEST_ASSERT_EQUAL_UINT8(expect[i][1], ev[i].state_to);
        TEST_ASSERT_EQUAL_INT32(expect[i][2], ev[i].arg);
    }
    TEST_ASSERT_EQUAL_UINT16(1000u, fake.pulse_us);
}

static void test_estop_cuts_the_esc_in_the_same_tick_and_latches(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    to_airborne(5000);
    run_ms(50);
    TEST_ASSERT_TRUE(fake.pulse_us > 1100u);
    verdict v = command(buf, frame_estop(buf, ++host_seq));
    TEST_ASSERT_TRUE(v.ack);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ESTOP, v.state);
    TEST_ASSERT_EQUAL_UINT16(1000u, fake.pulse_us);
    v = command(buf, frame_speed(buf, ++host_seq, 4000));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BAD_STATE, v.reason);
    v = command(buf, frame_disarm(buf, ++host_seq)); /* the rope still runs */
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BAD_STATE, v.reason);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ESTOP, rw_core_state(&core));
    set_rope_speed_mps(0.0);
    run_ms(300);
    TEST_ASSERT_TRUE(command(buf, frame_disarm(buf, ++host_seq)).ack);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_DISARMED, rw_core_state(&core));
}

/* Frame-level refusals: one bad datagram each while AIRBORNE; nothing changes but the counters. */
static void test_frame_level_nack_reasons_are_counted_and_harmless(void)
{
    uint8_t good[RW_MAX_FRAME_LEN];
    const size_t n = frame_speed(good, 0x0505u, 6000);
    to_airborne(4000);
    set_rope_speed_mps(4.0);
    heartbeat();
    run_ms(30);

    struct {
        int index; /* byte to patch, -1: none */
        uint8_t value;
        int len_delta; /* bytes removed (<0) or zero bytes appended (>0) */
        uint8_t reason;
    } cases[] = {
        { -1, 0u, -(int)n + 6, RW_NACK_REASON_TRUNCATED },
        { -1, 0u, -1, RW_NACK_REASON_TRUNCATED },
        { 0, 0x7Bu, 0, RW_NACK_REASON_BAD_MAGIC },
        { 1, (uint8_t)(RW_PROTOCOL_VERSION + 1u), 0, RW_NACK_REASON_BAD_VERSION },
        { 2, 0x02u, 0, RW_NACK_REASON_UNSUPPORTED_FLAGS }, /* a flag bit this version does not define */
        { 6, RW_MAX_PAYLOAD_LEN + 1u, 0, RW_NACK_REASON_OVERSIZE },
        { -1, 0u, 1, RW_NACK_REASON_BAD_LENGTH },
        { -1, 0u, 100, RW_NACK_REASON_BAD_LENGTH }, /* longer than any frame */
        { 8, 0x55u, 0, RW_NACK_REASON_BAD_CHECKSUM },
        { 3, 99u, 0, RW_NACK_REASON_UNKNOWN_MESSAGE },
    };
    for (unsigned c = 0u; c < sizeof cases / sizeof cases[0]; ++c) {
        uint8_t data[128];
        memset(data, 0, sizeof data);
        memcpy(data, good, n);
        if (cases[c].index >= 0) {
            data[cases[c].index] = cases[c].value;
        }
        size_t len = (size_t)((int)n + cases[c].len_delta);
        uint16_t rx_bad = core.state.counters.rx_bad;
        uint16_t nacks = core.state.counters.nacks;
        unsigned peers = fake.accept_peer_calls;
        verdict v = command_raw(data, len);
        TEST_ASSERT_FALSE_MESSAGE(v.ack, "a malformed datagram is never executed");
        TEST_ASSERT_EQUAL_UINT8_MESSAGE(cases[c].reason, v.reason, "NACK reason");
        TEST_ASSERT_EQUAL_UINT16(rx_bad + 1u, core.state.counters.rx_bad);
        TEST_ASSERT_EQUAL_UINT16(nacks + 1u, core.state.counters.nacks);
        TEST_ASSERT_EQUAL_UINT_MESSAGE(peers, fake.accept_peer_calls, "a bad datagram never becomes the peer");
        TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, rw_core_state(&core));
        TEST_ASSERT_EQUAL_FLOAT(4.0f, core.state.target_mps);
    }
    /* A device-to-host message sent to the device. */
    uint8_t buf[RW_MAX_FRAME_LEN];
    rw_msg_ack ack = { RW_MSG_ID_ARM, 1u, 1u };
    verdict v = command(buf, rw_msg_ack_encode(&ack, 9u, buf, sizeof buf));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_NOT_A_COMMAND, v.reason);
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_ACK, v.cmd_msg_id);
}

static void test_command_refusals_carry_their_detail(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    to_airborne(4000);
    set_rope_speed_mps(4.0);
    verdict v = command(buf, frame_speed(buf, ++host_seq, 20001));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, v.reason);
    TEST_ASSERT_EQUAL_INT32(20000, v.detail);
    v = command(buf, frame_speed(buf, ++host_seq, 0));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, v.reason);
    TEST_ASSERT_EQUAL_INT32(1, v.detail);
    v = command(buf, frame_speed(buf, ++host_seq, 2989));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BELOW_TOV_GUARD, v.reason);
    TEST_ASSERT_EQUAL_INT32(2990, v.detail);
    v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BAD_STATE, v.reason);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, v.state);
    v = command(buf, frame_param_get(buf, ++host_seq, (uint8_t)RW_PARAM_COUNT));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_UNKNOWN_PARAM, v.reason);
    v = command(buf, frame_param_set(buf, ++host_seq, RW_PARAM_ESC_MIN_US, 1100.0f));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_PARAM_LOCKED, v.reason);
    v = command(buf, frame_param_set(buf, ++host_seq, RW_PARAM_TOV_MPS, NAN));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, v.reason);
    TEST_ASSERT_EQUAL_FLOAT(4.0f, core.state.target_mps);
    TEST_ASSERT_EQUAL_FLOAT(1000.0f, rw_params_get(&core.params, RW_PARAM_ESC_MIN_US));
    TEST_ASSERT_EQUAL_FLOAT(2.6f, rw_params_get(&core.params, RW_PARAM_TOV_MPS));
    TEST_ASSERT_EQUAL_UINT16(7u, core.state.counters.nacks);
    TEST_ASSERT_EQUAL_UINT16(0u, core.state.counters.rx_bad);
    TEST_ASSERT_TRUE(command(buf, frame_speed(buf, ++host_seq, 2990)).ack);
}

static void test_retransmitted_param_set_is_executed_once(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    tick();
    size_t n = frame_param_set(buf, 77u, RW_PARAM_SPEED_KP, 0.07f);
    TEST_ASSERT_TRUE(command(buf, n).ack);
    run_ms(3);
    verdict again = command(buf, n);
    TEST_ASSERT_TRUE(again.ack);
    TEST_ASSERT_EQUAL_UINT16(77u, again.cmd_seq);
    drain();
    rw_msg_event ev[4];
    TEST_ASSERT_EQUAL_UINT(1u, events_of_kind(0u, RW_EVENT_KIND_PARAM_CHANGED, ev, 4u));
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_duplicates);
}

static void test_late_copy_of_an_old_speed_does_not_undo_a_newer_one(void)
{
    uint8_t five[RW_MAX_FRAME_LEN];
    uint8_t six[RW_MAX_FRAME_LEN];
    boot_and_arm();
    size_t n5 = frame_speed(five, 10u, 5000);
    size_t n6 = frame_speed(six, 11u, 6000);
    TEST_ASSERT_TRUE(command(five, n5).ack);
    TEST_ASSERT_TRUE(command(six, n6).ack);
    TEST_ASSERT_TRUE(command(five, n5).ack);
    TEST_ASSERT_EQUAL_FLOAT(6.0f, core.state.target_mps);
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_duplicates);
    /* Same seq, other bytes: a new command. */
    n6 = frame_speed(six, 10u, 7000);
    TEST_ASSERT_TRUE(command(six, n6).ack);
    TEST_ASSERT_EQUAL_FLOAT(7.0f, core.state.target_mps);
}

static void test_one_datagram_in_and_out_per_tick_and_outbox_priority(void)
{
    uint8_t a[RW_MAX_FRAME_LEN];
    uint8_t b[RW_MAX_FRAME_LEN];
    tick();
    run_ms(39); /* telemetry (50 Hz) is due at 40 ms */
    unsigned from = fake.n_out;
    queue_signed(a, frame_param_set(a, 1u, RW_PARAM_SPEED_KP, 0.05f));
    queue_signed(b, frame_param_get(b, 2u, RW_PARAM_TOV_MPS));
    tick();
    TEST_ASSERT_EQUAL_UINT(1u, fake.in_count);
    drain();
    /* t=40: ACK(1); 41: ACK(2) (each in its command's tick); then, signed over the idle ticks that follow,
     * PARAM_VALUE x2, EVENT(PARAM_CHANGED), TELEMETRY: replies, events, telemetry. */
    const uint8_t expect[] = { RW_MSG_ID_ACK, RW_MSG_ID_ACK, RW_MSG_ID_PARAM_VALUE, RW_MSG_ID_PARAM_VALUE,
                               RW_MSG_ID_EVENT, RW_MSG_ID_TELEMETRY };
    TEST_ASSERT_TRUE(fake.n_out >= from + 6u); /* the next telemetry may have followed while draining */
    for (unsigned i = 0u; i < 6u; ++i) {
        rw_frame f;
        TEST_ASSERT_EQUAL_UINT8(expect[i], sent_msg_id(from + i, &f));
    }
    TEST_ASSERT_EQUAL_UINT32(fake.out[from].tick + 1u, fake.out[from + 1u].tick);
    TEST_ASSERT_TRUE_MESSAGE(fake.out[from + 5u].tick - fake.out[from].tick <= 30u, "all out within 30 ms");
    TEST_ASSERT_EQUAL_UINT(1u, fake.out_this_tick_max);
}

static void test_heartbeat_loss_spins_down_after_the_timeout(void)
{
    to_airborne(4000);
    heartbeat();
    tick();
    uint32_t t_last = now_ms();
    for (uint32_t i = 0u; i < 600u && rw_core_state(&core) == RW_STATE_AIRBORNE; ++i) {
        set_rope_speed_mps((double)rw_speed_loop_setpoint_mps(&core.state.loop));
        tick();
    }
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_SPINDOWN, rw_core_state(&core));
    TEST_ASSERT_EQUAL_UINT32(t_last + 501u, now_ms());
    TEST_ASSERT_EQUAL_UINT8(RW_CAUSE_HEARTBEAT_LOST, core.state.spindown_cause);
    run_ms(10);
    rw_msg_event lost;
    TEST_ASSERT_EQUAL_UINT(1u, events_of_kind(0u, RW_EVENT_KIND_HEARTBEAT_LOST, &lost, 1u));
    TEST_ASSERT_EQUAL_INT32(501, lost.arg);
}

static void test_heartbeat_loss_while_armed_only_reports(void)
{
    boot_and_arm();
    run_ms(2000);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ARMED, rw_core_state(&core));
    rw_msg_event lost;
    TEST_ASSERT_EQUAL_UINT(1u, events_of_kind(0u, RW_EVENT_KIND_HEARTBEAT_LOST, &lost, 1u));
    TEST_ASSERT_EQUAL_UINT16(1000u, fake.pulse_us);
}

static void test_silent_encoder_with_throttle_up_faults(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    boot_and_arm();
    TEST_ASSERT_TRUE(command(buf, frame_speed(buf, ++host_seq, 5000)).ack);
    uint32_t t_up = 0u;
    for (uint32_t i = 0u; i < 1000u && rw_core_state(&core) != RW_STATE_FAULT; ++i) {
        if (t_up == 0u && fake.pulse_us > 1000u + RW_CORE_THROTTLE_ACTIVE_US) {
            t_up = now_ms();
        }
        tick();
    }
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_FAULT, rw_core_state(&core));
    TEST_ASSERT_TRUE(t_up > 0u);
    TEST_ASSERT_UINT32_WITHIN(2u, t_up + 251u, now_ms());
    TEST_ASSERT_EQUAL_UINT16(RW_FAULT_ENCODER_SILENT, core.state.fault_bits);
    TEST_ASSERT_EQUAL_UINT16(1000u, fake.pulse_us);
    run_ms(300);
    TEST_ASSERT_TRUE(command(buf, frame_disarm(buf, ++host_seq)).ack);
    TEST_ASSERT_EQUAL_UINT16(0u, core.state.fault_bits);
}

/* The same scenario with the tick clock starting at 0 and just before 2^32: identical pulses. */
static void record_scenario(uint32_t offset_us, uint16_t *pulses, unsigned n)
{
    setUp();
    fake.clock_offset_us = offset_us;
    fake.last_edge_us = offset_us;
    uint8_t buf[RW_MAX_FRAME_LEN];
    unsigned k = 0u;
    tick();
    pulses[k++] = fake.pulse_us;
    while (k < n) {
        if (k == 520u) {
            queue_signed(buf, frame_arm(buf, ++host_seq));
        } else if (k == 530u) {
            queue_signed(buf, frame_speed(buf, ++host_seq, 4000));
        } else if (k % 100u == 0u) {
            heartbeat();
        }
        set_rope_speed_mps((double)rw_speed_loop_setpoint_mps(&core.state.loop));
        tick();
        pulses[k++] = fake.pulse_us;
    }
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, rw_core_state(&core));
}

static void test_tick_clock_wrap_changes_nothing(void)
{
    static uint16_t ref[1500];
    static uint16_t wrapped[1500];
    record_scenario(0u, ref, 1500u);
    unsigned n_ref = fake.n_out;
    record_scenario(0xFFFFFFFFu - 700000u, wrapped, 1500u); /* wraps at 700 ms, mid spin-up */
    TEST_ASSERT_EQUAL_UINT(n_ref, fake.n_out);
    TEST_ASSERT_EQUAL_UINT16_ARRAY(ref, wrapped, 1500u);
}

/* A 10 s pause between two ticks (debugger, stalled loop) is integrated as one short control step: the
 * ESC pulse moves by a normal step, not by 10 s of integral (which would saturate it). */
static void test_long_tick_gap_does_not_jump_the_esc_pulse(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_core_set_param(&core, RW_PARAM_HEARTBEAT_TIMEOUT_S, 10.0f));
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_core_set_param(&core, RW_PARAM_RAMP_UP_MPS2, 2.0f));
    /* the first tick loads the stored parameters over the core's: store these (as provisioning would) */
    rw_config_set_params(&flash, core.params.value);
    to_airborne(4000);
    for (uint32_t i = 0u; i < 2000u && rw_speed_loop_setpoint_mps(&core.state.loop) < 4.0f; ++i) {
        set_rope_speed_mps((double)rw_speed_loop_setpoint_mps(&core.state.loop));
        tick();
    }
    TEST_ASSERT_TRUE(command(buf, frame_speed(buf, ++host_seq, 8000)).ack);
    set_rope_speed_mps(4.0); /* the rope is loaded: held at 4 m/s while the setpoint ramps on */
    run_ms(100);
    const uint16_t before = fake.pulse_us;
    heartbeat();
    fake.t_ns += 10000000000ull - (uint64_t)TICK_US * 1000u; /* tick() adds the last millisecond */
    tick();
    TEST_ASSERT_UINT16_WITHIN(60u, before, fake.pulse_us);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, rw_core_state(&core));
    TEST_ASSERT_FLOAT_WITHIN(0.1f, 4.0f, core.state.measured_mps);
}

static size_t frame_simple(uint8_t *buf, uint8_t msg_id, uint16_t seq)
{
    return rw_frame_encode(msg_id, seq, NULL, 0u, buf, RW_MAX_FRAME_LEN);
}

static void test_spindle_refusals(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    /* No spindle fitted: SPINDLE_UNAVAILABLE. */
    tick();
    run_ms(600);
    verdict v = command(buf, frame_simple(buf, RW_MSG_ID_HOME, ++host_seq));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_SPINDLE_UNAVAILABLE, v.reason);
    /* A spindle that was never homed: NOT_HOMED for GRASP, nothing changes. */
    setUp();
    hal = &hal_with_spindle;
    to_airborne(4000);
    v = command(buf, frame_simple(buf, RW_MSG_ID_GRASP, ++host_seq));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_NOT_HOMED, v.reason);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, rw_core_state(&core));
    /* SET_LOOP out of range: detail = the limit, um (checked before homing). */
    rw_msg_set_loop loop = { 180001 };
    v = command(buf, rw_msg_set_loop_encode(&loop, ++host_seq, buf, sizeof buf));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_OUT_OF_RANGE, v.reason);
    TEST_ASSERT_EQUAL_INT32(180000, v.detail);
    TEST_ASSERT_TRUE(spindle_fake.writes > 0u);
    TEST_ASSERT_EQUAL_UINT16(0u, spindle_fake.last_raw);
}

/* ---- the signed link ------------------------------------------------------------------------------ */

/* Ticks once with the datagram queued; true if the core replied (ACK/NACK) in that tick. */
static bool answered(const uint8_t *datagram, size_t len)
{
    unsigned from = fake.n_out;
    queue_bytes(datagram, len);
    tick();
    for (unsigned i = from; i < fake.n_out; ++i) {
        if (fake.out[i].reply) {
            return true;
        }
    }
    return false;
}

static void test_boot_counter_is_the_session_and_is_stored_at_once(void)
{
    tick();
    TEST_ASSERT_EQUAL_UINT32(1u, rw_core_session_id(&core));
    TEST_ASSERT_EQUAL_UINT(1u, flash_saves);
    TEST_ASSERT_TRUE(rw_config_valid(&flash));
    TEST_ASSERT_EQUAL_UINT32(1u, flash.boot_counter);
    TEST_ASSERT_EQUAL_UINT8(1u, flash.key_set);
    /* the next boot of the same device is session 2: frames of session 1 no longer count */
    uint8_t buf[RW_MAX_FRAME_LEN];
    uint8_t old[RW_MAX_FRAME_LEN];
    size_t n_old = sign_frame(old, buf, frame_param_get(buf, ++host_seq, RW_PARAM_TOV_MPS));
    rw_core_init(&core);
    tick();
    TEST_ASSERT_EQUAL_UINT32(2u, rw_core_session_id(&core));
    TEST_ASSERT_EQUAL_UINT32(2u, flash.boot_counter);
    TEST_ASSERT_FALSE(answered(old, n_old));
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_replayed);
    TEST_ASSERT_TRUE(command(buf, frame_param_get(buf, ++host_seq, RW_PARAM_TOV_MPS)).ack);
}

static void test_unsigned_forged_and_replayed_frames_are_dropped_and_counted(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    uint8_t accepted[RW_MAX_FRAME_LEN];
    tick();
    run_ms(600); /* past the arming hold */
    size_t n_acc = sign_frame(accepted, buf, frame_param_get(buf, ++host_seq, RW_PARAM_TOV_MPS));
    TEST_ASSERT_TRUE(answered(accepted, n_acc));
    unsigned peers = fake.accept_peer_calls;

    /* unsigned ARM: dropped (the core stays DISARMED) */
    size_t n = frame_arm(buf, ++host_seq);
    TEST_ASSERT_FALSE(answered(buf, n));
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_auth_failed);
    /* forged: signed ARM with one tag bit flipped */
    uint8_t forged[RW_MAX_FRAME_LEN];
    size_t n_forged = sign_frame(forged, buf, frame_arm(buf, ++host_seq));
    forged[n_forged - 1u] ^= 0x80u;
    TEST_ASSERT_FALSE(answered(forged, n_forged));
    TEST_ASSERT_EQUAL_UINT16(2u, core.state.counters.rx_auth_failed);
    /* signed with another key */
    uint8_t other_key[RW_KEY_LEN];
    memcpy(other_key, test_key, sizeof other_key);
    other_key[0] ^= 1u;
    uint8_t foreign[RW_MAX_FRAME_LEN];
    size_t n_foreign = frame_arm(foreign, ++host_seq);
    n_foreign = rw_frame_sign(foreign, n_foreign, sizeof foreign, host_session_id(), ++host_counter, other_key);
    TEST_ASSERT_FALSE(answered(foreign, n_foreign));
    TEST_ASSERT_EQUAL_UINT16(3u, core.state.counters.rx_auth_failed);
    /* the identical bytes of the accepted frame again, and a counter not above the last accepted */
    TEST_ASSERT_FALSE(answered(accepted, n_acc));
    uint8_t stale[RW_MAX_FRAME_LEN];
    size_t n_stale = frame_arm(stale, ++host_seq);
    n_stale = rw_frame_sign(stale, n_stale, sizeof stale, host_session_id(), 1u, test_key);
    TEST_ASSERT_FALSE(answered(stale, n_stale));
    TEST_ASSERT_EQUAL_UINT16(2u, core.state.counters.rx_replayed);
    TEST_ASSERT_EQUAL_UINT16(3u, core.state.counters.rx_auth_failed);

    TEST_ASSERT_EQUAL_UINT8(RW_STATE_DISARMED, rw_core_state(&core));
    TEST_ASSERT_EQUAL_UINT_MESSAGE(peers, fake.accept_peer_calls, "a dropped frame never becomes the peer");
    TEST_ASSERT_EQUAL_UINT16(0u, core.state.counters.nacks);
    /* the genuine host is still heard */
    verdict v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_TRUE(v.ack);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_ARMED, v.state);
}

static void test_without_a_key_nothing_but_hello_is_accepted_over_wifi(void)
{
    rw_config_defaults(&flash); /* an unprovisioned device */
    uint8_t buf[RW_MAX_FRAME_LEN];
    uint8_t signed_frame[RW_MAX_FRAME_LEN];
    tick();
    size_t n_signed = sign_frame(signed_frame, buf, frame_param_get(buf, ++host_seq, RW_PARAM_TOV_MPS));
    TEST_ASSERT_FALSE(answered(signed_frame, n_signed));
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_auth_failed);
    rw_msg_hello hello;
    memset(&hello, 0, sizeof hello);
    size_t n = rw_msg_hello_encode(&hello, ++host_seq, buf, sizeof buf);
    TEST_ASSERT_TRUE_MESSAGE(answered(buf, n), "HELLO is answered unsigned (SESSION_INFO)");
    rw_frame f;
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_SESSION_INFO, sent_msg_id(fake.n_out - 1u, &f));
    TEST_ASSERT_EQUAL_UINT8(0u, f.flags & RW_FRAME_FLAG_SIGNED);
}

/* ---- parameters staged to a tick boundary, the flash written outside the tick ------------------------ */

/* A PARAM_SET is ACKed with the value stored, its module (the PI) converted at the end of the next tick that
 * takes no datagram: the speed step of the PARAM_SET's own tick still runs the old gain, whole. */
static void test_param_set_is_converted_at_the_next_quiet_tick(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    to_airborne(4000);
    const int32_t kp_before = core.state.loop.pi.state.kp_q24;
    TEST_ASSERT_TRUE(command(buf, frame_param_set(buf, ++host_seq, RW_PARAM_SPEED_KP, 0.08f)).ack);
    TEST_ASSERT_EQUAL_FLOAT(0.08f, rw_params_get(&core.params, RW_PARAM_SPEED_KP));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_SPEED_PI, rw_core_params_pending(&core));
    TEST_ASSERT_EQUAL_INT32(kp_before, core.state.loop.pi.state.kp_q24);
    tick(); /* no datagram: the PI is converted at its end */
    TEST_ASSERT_EQUAL_HEX16(0u, rw_core_params_pending(&core));
    TEST_ASSERT_EQUAL_INT32((int32_t)(0.08f * 16777216.0f + 0.5f), core.state.loop.pi.state.kp_q24);
    TEST_ASSERT_TRUE(kp_before != core.state.loop.pi.state.kp_q24);
    TEST_ASSERT_EQUAL_UINT8(RW_STATE_AIRBORNE, rw_core_state(&core));
}

/* Datagrams in every tick: a staged module waits at most RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS of them. */
static void test_param_set_waits_a_bounded_time_under_a_datagram_every_tick(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    tick();
    TEST_ASSERT_TRUE(command(buf, frame_param_set(buf, ++host_seq, RW_PARAM_RAMP_UP_MPS2, 40.0f)).ack);
    unsigned ticks = 0u;
    while (rw_core_params_pending(&core) != 0u && ticks < 100u) {
        heartbeat();
        tick();
        ++ticks;
    }
    TEST_ASSERT_EQUAL_HEX16(0u, rw_core_params_pending(&core));
    /* the PARAM_SET's tick and 19 heartbeat ticks waited (RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS = 20), the 20th
     * heartbeat tick converts it although it took a datagram */
    TEST_ASSERT_EQUAL_UINT(20u, ticks);
}

/* SET_ROPE_SPEED right after a PARAM_SET that raised the guard is checked against the new guard. */
static void test_a_command_after_a_guard_change_sees_the_new_guard(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    to_airborne(6000);
    TEST_ASSERT_TRUE(command(buf, frame_param_set(buf, ++host_seq, RW_PARAM_TOV_MPS, 5.0f)).ack); /* guard 5.75 */
    verdict v = command(buf, frame_speed(buf, ++host_seq, 5500));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_BELOW_TOV_GUARD, v.reason);
    TEST_ASSERT_EQUAL_INT32(5750, v.detail);
}

static void serial_queue(const uint8_t *frame, size_t len)
{
    TEST_ASSERT_EQUAL_UINT(0u, serial_fake.in_len);
    TEST_ASSERT_TRUE(len <= sizeof serial_fake.in);
    memcpy(serial_fake.in, frame, len);
    serial_fake.in_len = len;
}

static size_t frame_commit(uint8_t *buf, uint16_t seq, uint32_t epoch)
{
    rw_msg_provision_commit m = { .session_epoch = epoch };
    return rw_msg_provision_commit_encode(&m, seq, buf, RW_MAX_FRAME_LEN);
}

/* PROVISION_COMMIT: answered only once the store wrote the record; ARM refused NOT_READY meanwhile; the new
 * session in force from the answer on; a retransmission meanwhile is not executed again. */
static void test_commit_is_answered_when_the_flash_is_written(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    hal = &hal_with_serial;
    tick();
    run_ms(600);
    const unsigned saves_at_boot = flash_saves;
    flash_hold = true;
    size_t n = frame_commit(buf, 7u, 4242u);
    serial_queue(buf, n);
    tick();
    TEST_ASSERT_EQUAL_UINT(0u, serial_fake.replies);
    TEST_ASSERT_EQUAL_UINT(saves_at_boot, flash_saves);
    verdict v = command(buf, frame_arm(buf, ++host_seq));
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_NOT_READY, v.reason);
    n = frame_commit(buf, 7u, 4242u); /* the host retransmits */
    serial_queue(buf, n);
    tick();
    TEST_ASSERT_EQUAL_UINT(0u, serial_fake.replies);
    TEST_ASSERT_EQUAL_UINT16(1u, core.state.counters.rx_duplicates);
    run_ms(20);
    TEST_ASSERT_EQUAL_UINT(0u, serial_fake.replies);
    flash_release();
    tick();
    TEST_ASSERT_EQUAL_UINT(1u, serial_fake.replies);
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_ACK, serial_fake.last_msg_id);
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_PROVISION_COMMIT, serial_fake.last_cmd_msg_id);
    TEST_ASSERT_EQUAL_UINT(saves_at_boot + 1u, flash_saves);
    TEST_ASSERT_EQUAL_UINT32(4242u, rw_core_session_id(&core));
    TEST_ASSERT_EQUAL_UINT32(4242u, flash.session_epoch);
    TEST_ASSERT_EQUAL_UINT32(1u, flash.commits);
    /* the retransmission again: the cached ACK, no second write */
    serial_queue(buf, n);
    tick();
    TEST_ASSERT_EQUAL_UINT(2u, serial_fake.replies);
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_ACK, serial_fake.last_msg_id);
    TEST_ASSERT_EQUAL_UINT(saves_at_boot + 1u, flash_saves);
}

/* A failed write: NACK STORE_FAILED (detail 1), session and record unchanged. */
static void test_a_failed_commit_write_changes_nothing(void)
{
    uint8_t buf[RW_MAX_FRAME_LEN];
    hal = &hal_with_serial;
    tick();
    const uint32_t session = rw_core_session_id(&core);
    flash_fail = true;
    serial_queue(buf, frame_commit(buf, 3u, 777u));
    tick();
    TEST_ASSERT_EQUAL_UINT(1u, serial_fake.replies);
    TEST_ASSERT_EQUAL_UINT8(RW_MSG_ID_NACK, serial_fake.last_msg_id);
    TEST_ASSERT_EQUAL_UINT8(RW_NACK_REASON_STORE_FAILED, serial_fake.last_reason);
    TEST_ASSERT_EQUAL_INT32(1, serial_fake.last_detail);
    TEST_ASSERT_EQUAL_UINT32(session, rw_core_session_id(&core));
    TEST_ASSERT_EQUAL_UINT32(0u, core.state.config.commits);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_arm_refused_not_ready_during_hold_then_accepted);
    RUN_TEST(test_full_cycle_transitions_and_causes);
    RUN_TEST(test_estop_cuts_the_esc_in_the_same_tick_and_latches);
    RUN_TEST(test_frame_level_nack_reasons_are_counted_and_harmless);
    RUN_TEST(test_command_refusals_carry_their_detail);
    RUN_TEST(test_retransmitted_param_set_is_executed_once);
    RUN_TEST(test_late_copy_of_an_old_speed_does_not_undo_a_newer_one);
    RUN_TEST(test_one_datagram_in_and_out_per_tick_and_outbox_priority);
    RUN_TEST(test_heartbeat_loss_spins_down_after_the_timeout);
    RUN_TEST(test_heartbeat_loss_while_armed_only_reports);
    RUN_TEST(test_silent_encoder_with_throttle_up_faults);
    RUN_TEST(test_tick_clock_wrap_changes_nothing);
    RUN_TEST(test_long_tick_gap_does_not_jump_the_esc_pulse);
    RUN_TEST(test_spindle_refusals);
    RUN_TEST(test_boot_counter_is_the_session_and_is_stored_at_once);
    RUN_TEST(test_param_set_is_converted_at_the_next_quiet_tick);
    RUN_TEST(test_param_set_waits_a_bounded_time_under_a_datagram_every_tick);
    RUN_TEST(test_a_command_after_a_guard_change_sees_the_new_guard);
    RUN_TEST(test_commit_is_answered_when_the_flash_is_written);
    RUN_TEST(test_a_failed_commit_write_changes_nothing);
    RUN_TEST(test_unsigned_forged_and_replayed_frames_are_dropped_and_counted);
    RUN_TEST(test_without_a_key_nothing_but_hello_is_accepted_over_wifi);
    return UNITY_END();
}
