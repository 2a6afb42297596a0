/* Received frames: decode, refuse with a reason, drop retransmissions, execute commands.
 *
 * Every frame gets exactly one verdict. Malformed frames and device-to-host messages: NACK to the
 * sender, counted in rx_bad. Commands: executed once; a retransmission (same msg_id, seq and checksum
 * within RW_DUPLICATE_WINDOW_MS) gets the cached verdict again and is counted in rx_duplicates. Nothing
 * is ever clamped: a value out of range is refused with OUT_OF_RANGE and the limit in NACK.detail. */
#include <math.h>
#include <string.h>

#include "rw_core_internal.h"

typedef struct verdict {
    uint8_t reason; /* 0 = ACK */
    int32_t detail;
    bool later;     /* no answer now: a PROVISION_COMMIT being written (rw_core_provision_poll answers it) */
} verdict;

static const verdict ACCEPT = { 0u, 0, false };
static const verdict LATER = { 0u, 0, true };

static verdict refuse(uint8_t reason, int32_t detail)
{
    verdict v = { reason, detail, false };
    return v;
}

static bool rope_stopped(const rw_core *core)
{
    return core->state.measured_mps < RW_CORE_STOPPED_MPS;
}

static verdict cmd_arm(rw_core *core)
{
    switch (core->state.state) {
    case RW_STATE_ARMED:
        return ACCEPT;
    case RW_STATE_DISARMED:
        if (!core->state.arming_hold_done) {
            return refuse(RW_NACK_REASON_NOT_READY,
                          (int32_t)(rw_params_get(&core->params, RW_PARAM_ARM_HOLD_S) * 1000.0f));
        }
        if (core->state.commit_pending) { /* the rope stays down while the flash is written (it stalls the CPU) */
            return refuse(RW_NACK_REASON_NOT_READY, 0);
        }
        rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_COMMAND);
        return ACCEPT;
    default:
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
}

static verdict cmd_disarm(rw_core *core)
{
    switch (core->state.state) {
    case RW_STATE_DISARMED:
    case RW_STATE_ARMED:
    case RW_STATE_RELAX:
    case RW_STATE_FAULT:
    case RW_STATE_ESTOP:
        if (!rope_stopped(core)) {
            return refuse(RW_NACK_REASON_BAD_STATE, (int32_t)(core->state.measured_mps * 1000.0f));
        }
        rw_spindle_stop(&core->state.spindle);
        if (core->state.fault_bits != 0u) {
            uint8_t st = core->state.state;
            rw_core_emit_event(core, RW_EVENT_KIND_FAULT_CLEARED, st, st, (int32_t)core->state.fault_bits);
            core->state.fault_bits = 0u;
        }
        rw_core_set_state(core, RW_STATE_DISARMED, RW_CAUSE_COMMAND);
        return ACCEPT;
    default:
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
}

static verdict cmd_set_rope_speed(rw_core *core, const rw_msg_set_rope_speed *msg)
{
    int32_t max_mmps = (int32_t)(rw_params_get(&core->params, RW_PARAM_MAX_ROPE_SPEED_MPS) * 1000.0f + 0.5f);
    if (msg->rope_speed_mmps <= 0) {
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, 1);
    }
    if (msg->rope_speed_mmps > max_mmps) {
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, max_mmps);
    }
    if ((core->state.fault_bits & (RW_FAULT_BATTERY_LOW | RW_FAULT_LOAD_LOST)) != 0u) {
        return refuse(RW_NACK_REASON_BAD_STATE, (int32_t)core->state.fault_bits);
    }
    float target_mps = (float)msg->rope_speed_mmps * 1.0e-3f;
    uint8_t st = core->state.state;
    switch (st) {
    case RW_STATE_AIRBORNE: {
        float guard_mps = rw_tov_guard_min_airborne_mps(&core->state.guard);
        if (!rw_tov_guard_setpoint_allowed(&core->state.guard, target_mps)) {
            return refuse(RW_NACK_REASON_BELOW_TOV_GUARD, (int32_t)ceilf(guard_mps * 1000.0f));
        }
        core->state.target_mps = target_mps;
        return ACCEPT;
    }
    case RW_STATE_ARMED:
    case RW_STATE_SPINUP:
    case RW_STATE_SPINDOWN:
        core->state.target_mps = target_mps;
        rw_core_set_state(core, RW_STATE_SPINUP, RW_CAUSE_COMMAND);
        return ACCEPT;
    default:
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
}

static verdict cmd_spindown(rw_core *core)
{
    switch (core->state.state) {
    case RW_STATE_SPINUP:
    case RW_STATE_AIRBORNE:
    case RW_STATE_RELAX:
        core->state.grasp_pending = false;
        core->state.target_mps = 0.0f;
        rw_core_set_state(core, RW_STATE_SPINDOWN, RW_CAUSE_COMMAND);
        return ACCEPT;
    case RW_STATE_DISARMED:
    case RW_STATE_ARMED:
    case RW_STATE_SPINDOWN:
        return ACCEPT;
    default:
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
}

/* ESTOP stops the rope (the ESC minimum, in this tick's control step) and the spindle in the tick it arrives:
 * the servo is written at once, not at the next spindle step (up to RW_CORE_SPINDLE_PERIOD_MS later). */
static verdict cmd_estop(rw_core *core, const rw_hal *hal)
{
    core->state.target_mps = 0.0f;
    core->state.grasp_pending = false;
    rw_spindle_stop(&core->state.spindle);
    if (hal->spindle != NULL) {
        hal->spindle->write_moving_speed_raw(hal->spindle->ctx, 0u);
    }
    rw_core_set_state(core, RW_STATE_ESTOP, RW_CAUSE_COMMAND);
    return ACCEPT;
}

static verdict cmd_param_set(rw_core *core, const rw_msg_param_set *msg)
{
    /* While airborne the guard may not rise over the current target: land or raise the target first. */
    if (core->state.state == RW_STATE_AIRBORNE &&
        (msg->param_id == RW_PARAM_TOV_MPS || msg->param_id == RW_PARAM_TOV_MARGIN) &&
        rw_params_check(&core->params, msg->param_id, msg->value, false) == RW_DECODE_OK) {
        float tov = msg->param_id == RW_PARAM_TOV_MPS ? msg->value : rw_params_get(&core->params, RW_PARAM_TOV_MPS);
        float margin = msg->param_id == RW_PARAM_TOV_MARGIN ? msg->value : rw_params_get(&core->params, RW_PARAM_TOV_MARGIN);
        float guard_mps = tov * margin;
        if (core->state.target_mps < guard_mps) {
            return refuse(RW_NACK_REASON_BELOW_TOV_GUARD, (int32_t)ceilf(guard_mps * 1000.0f));
        }
    }
    int result = rw_core_set_param(core, msg->param_id, msg->value);
    if (result == RW_NACK_REASON_PARAM_CONFLICT) { /* detail: the other parameter of the rule */
        return refuse((uint8_t)result, rw_params_conflict(&core->params, msg->param_id, msg->value));
    }
    if (result != RW_DECODE_OK) {
        return refuse((uint8_t)result, msg->param_id);
    }
    uint8_t st = core->state.state;
    rw_core_emit_event(core, RW_EVENT_KIND_PARAM_CHANGED, st, st, msg->param_id);
    return ACCEPT;
}


/* ---- spindle and grasp ------------------------------------------------------------------------- */

static verdict spindle_usable(const rw_core *core, const rw_hal *hal, bool need_homed)
{
    if (hal->spindle == NULL || (core->state.fault_bits & (RW_FAULT_SPINDLE_NO_ANSWER | RW_FAULT_SPINDLE_STALL)) != 0u) {
        return refuse(RW_NACK_REASON_SPINDLE_UNAVAILABLE, (int32_t)core->state.fault_bits);
    }
    if (need_homed && !rw_spindle_is_homed(&core->state.spindle)) {
        return refuse(RW_NACK_REASON_NOT_HOMED, 0);
    }
    return ACCEPT;
}

static verdict cmd_home(rw_core *core, const rw_hal *hal)
{
    uint8_t st = core->state.state;
    if ((st != RW_STATE_DISARMED && st != RW_STATE_ARMED) || !rope_stopped(core)) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    verdict v = spindle_usable(core, hal, false);
    if (v.reason == 0u) {
        rw_spindle_home(&core->state.spindle);
    }
    return v;
}

static verdict cmd_set_loop(rw_core *core, const rw_hal *hal, const rw_msg_set_loop *msg)
{
    uint8_t st = core->state.state;
    if (st != RW_STATE_ARMED && st != RW_STATE_SPINUP && st != RW_STATE_AIRBORNE) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    int32_t min_um = (int32_t)(rw_params_get(&core->params, RW_PARAM_GUIDE_MIN_MM) * 1000.0f + 0.5f);
    int32_t max_um = (int32_t)(rw_params_get(&core->params, RW_PARAM_GUIDE_MAX_MM) * 1000.0f + 0.5f);
    if (msg->guide_position_um < min_um) {
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, min_um);
    }
    if (msg->guide_position_um > max_um) {
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, max_um);
    }
    verdict v = spindle_usable(core, hal, true);
    if (v.reason == 0u) {
        rw_spindle_move_to(&core->state.spindle, (float)msg->guide_position_um * 1.0e-3f);
    }
    return v;
}

static verdict cmd_relax(rw_core *core, bool then_grasp)
{
    uint8_t st = core->state.state;
    if (then_grasp ? st != RW_STATE_AIRBORNE : (st != RW_STATE_SPINUP && st != RW_STATE_AIRBORNE)) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    core->state.grasp_pending = then_grasp;
    core->state.target_mps = 0.0f;
    rw_spindle_stop(&core->state.spindle);
    rw_core_set_state(core, RW_STATE_RELAX, RW_CAUSE_COMMAND);
    return ACCEPT;
}

static verdict cmd_grasp(rw_core *core, const rw_hal *hal)
{
    verdict v = spindle_usable(core, hal, true);
    return v.reason != 0u ? v : cmd_relax(core, true);
}

static verdict cmd_retract(rw_core *core, const rw_hal *hal)
{
    uint8_t st = core->state.state;
    if ((st != RW_STATE_RELAX && st != RW_STATE_ARMED) || !rope_stopped(core)) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    verdict v = spindle_usable(core, hal, true);
    if (v.reason == 0u) {
        core->state.grasp_pending = false;
        rw_spindle_retract(&core->state.spindle);
        rw_core_set_state(core, RW_STATE_RETRACT, RW_CAUSE_COMMAND);
    }
    return v;
}

static verdict cmd_release(rw_core *core, const rw_hal *hal)
{
    if (core->state.state != RW_STATE_HOLD) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    verdict v = spindle_usable(core, hal, true);
    if (v.reason == 0u) {
        /* extend by release_mm, not past the home-end soft limit */
        float target = core->state.spindle.state.position_mm - rw_params_get(&core->params, RW_PARAM_RELEASE_MM);
        float min_mm = rw_params_get(&core->params, RW_PARAM_GUIDE_MIN_MM);
        rw_spindle_move_to(&core->state.spindle, target < min_mm ? min_mm : target);
        rw_core_set_state(core, RW_STATE_ARMED, RW_CAUSE_COMMAND);
    }
    return v;
}

static verdict execute(rw_core *core, const rw_hal *hal, const rw_frame *frame)
{
    /* the modules the commands check against (the guard, the spindle's limits) hold every staged change */
    rw_core_params_settle(core, RW_PARAM_MODULE_TOV_GUARD | RW_PARAM_MODULE_SPINDLE);
    switch (frame->msg_id) {
    case RW_MSG_ID_ARM:
        return cmd_arm(core);
    case RW_MSG_ID_DISARM:
        return cmd_disarm(core);
    case RW_MSG_ID_SET_ROPE_SPEED: {
        rw_msg_set_rope_speed msg;
        rw_msg_set_rope_speed_unpack(&msg, frame->payload);
        return cmd_set_rope_speed(core, &msg);
    }
    case RW_MSG_ID_SPINDOWN:
        return cmd_spindown(core);
    case RW_MSG_ID_ESTOP:
        return cmd_estop(core, hal);
    case RW_MSG_ID_PARAM_GET: {
        rw_msg_param_get msg;
        rw_msg_param_get_unpack(&msg, frame->payload);
        return msg.param_id < RW_PARAM_COUNT ? ACCEPT : refuse(RW_NACK_REASON_UNKNOWN_PARAM, msg.param_id);
    }
    case RW_MSG_ID_PARAM_SET: {
        rw_msg_param_set msg;
        rw_msg_param_set_unpack(&msg, frame->payload);
        return cmd_param_set(core, &msg);
    }
    case RW_MSG_ID_HOME:
        return cmd_home(core, hal);
    case RW_MSG_ID_SET_LOOP: {
        rw_msg_set_loop msg;
        rw_msg_set_loop_unpack(&msg, frame->payload);
        return cmd_set_loop(core, hal, &msg);
    }
    case RW_MSG_ID_RELAX:
        return cmd_relax(core, false);
    case RW_MSG_ID_GRASP:
        return cmd_grasp(core, hal);
    case RW_MSG_ID_RETRACT:
        return cmd_retract(core, hal);
    case RW_MSG_ID_RELEASE:
        return cmd_release(core, hal);
    case RW_MSG_ID_BURST_START: {
        rw_msg_burst_start msg;
        rw_msg_burst_start_unpack(&msg, frame->payload);
        int32_t detail = 0;
        const uint8_t reason = rw_burst_start(&core->state.burst, msg.samples, &detail);
        return reason == 0u ? ACCEPT : refuse(reason, detail);
    }
    default:
        return refuse(RW_NACK_REASON_NOT_A_COMMAND, 0);
    }
}

static void send_verdict(rw_core *core, const rw_hal *hal, rw_link_id link, uint8_t msg_id, uint16_t seq, verdict v)
{
    uint8_t frame[RW_MAX_FRAME_LEN];
    size_t len;
    if (v.reason == 0u) {
        rw_msg_ack ack = { .cmd_msg_id = msg_id, .cmd_seq = seq, .state = core->state.state };
        len = rw_msg_ack_encode(&ack, rw_core_take_seq(core, link), frame, sizeof frame);
    } else {
        rw_msg_nack nack = {
            .cmd_msg_id = msg_id, .cmd_seq = seq, .reason = v.reason, .state = core->state.state, .detail = v.detail,
        };
        len = rw_msg_nack_encode(&nack, rw_core_take_seq(core, link), frame, sizeof frame);
        ++core->state.counters.nacks;
    }
    rw_core_link_send(core, hal, link, true, frame, len);
}

/* ---- session and provisioning ------------------------------------------------------------------ */

static void reply_session_info(rw_core *core, const rw_hal *hal, rw_link_id link, const rw_frame *frame)
{
    rw_msg_hello hello;
    rw_msg_hello_unpack(&hello, frame->payload);
    rw_msg_session_info info = {
        .host_nonce = hello.host_nonce,
        .session_id = rw_core_session_id(core),
        .key_set = core->state.config.key_set,
        .schema_hash = (uint16_t)RW_PROTOCOL_SCHEMA_HASH,
    };
    uint8_t out[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_session_info_encode(&info, rw_core_take_seq(core, link), out, sizeof out);
    rw_core_link_send(core, hal, link, true, out, len);
}

static void queue_provision_status(rw_core *core)
{
    const rw_config *c = &core->state.config;
    rw_msg_provision_status st = {
        .key_set = c->key_set,
        .password_set = c->password_set,
        .boot_counter = c->boot_counter,
        .commits = c->commits,
        .config_version = (uint16_t)RW_CONFIG_VERSION,
        .dirty = core->state.config_dirty ? 1u : 0u,
    };
    memcpy(st.wifi_ssid, c->wifi_ssid, sizeof st.wifi_ssid);
    uint8_t out[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_provision_status_encode(&st, 0u, out, sizeof out); /* numbered when it leaves */
    rw_outbox_push(&core->state.outbox, RW_OUTBOX_REPLY, out, len);
}

/* The committed record takes effect: a new session at once (epoch + 0), so no frame signed for an earlier
 * session or provisioning counts; the staged key is forgotten (it is in the record now). */
static void commit_done(rw_core *core)
{
    const rw_config *next = &core->state.commit_record;
    if (core->state.key_staged) {
        core->state.key_staged = false;
        memset(core->state.staged_key, 0, RW_KEY_LEN);
    }
    core->state.session_id = rw_config_session_id(next);
    core->state.host_counter = 0u;
    for (unsigned i = 0u; i < 2u; ++i) {
        if (rw_signer_busy(&core->state.signers[i])) { /* signed for the old session (and key): it would be refused */
            rw_signer_reset(&core->state.signers[i]);
            rw_outbox_count_drop(&core->state.outbox);
        }
    }
    core->state.signer_head = 0u;
    core->state.config = *next;
    core->state.config_dirty = false;
    rw_core_link_prepare_key(core);
}

bool rw_core_provision_poll(rw_core *core, const rw_hal *hal)
{
    if (!core->state.commit_pending) {
        return false;
    }
    const uint8_t status = hal->config->save_status(hal->config->ctx);
    if (status == RW_CONFIG_SAVE_BUSY) {
        return false;
    }
    core->state.commit_pending = false;
    verdict v = ACCEPT;
    if (status == RW_CONFIG_SAVE_DONE) {
        commit_done(core);
    } else {
        v = refuse(RW_NACK_REASON_STORE_FAILED, 1); /* nothing changed */
    }
    rw_duplicate_cache_store(&core->state.duplicates, core->state.commit_msg_id, core->state.commit_seq,
                             core->state.commit_checksum, v.reason, v.detail, core->state.uptime_ms);
    send_verdict(core, hal, (rw_link_id)core->state.commit_link, core->state.commit_msg_id, core->state.commit_seq, v);
    return true;
}

/* PROVISION_COMMIT: the new record (a fresh epoch, the parameters, the staged key) is handed to the store,
 * which writes it outside the tick; the command is answered when the store says it is written
 * (rw_core_provision_poll), in this tick already if the store wrote it at once. */
static verdict commit(rw_core *core, const rw_hal *hal, rw_link_id link, const rw_frame *frame)
{
    const rw_config *c = &core->state.config;
    if (hal->config == NULL || hal->config->request_save == NULL || hal->config->save_status == NULL) {
        return refuse(RW_NACK_REASON_STORE_FAILED, 0);
    }
    rw_msg_provision_commit msg;
    rw_msg_provision_commit_unpack(&msg, frame->payload);
    if (c->commits != 0u && msg.session_epoch == c->session_epoch) {
        /* the same epoch again would restart the same session ids, whose frames could then be replayed */
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, (int32_t)msg.session_epoch);
    }
    rw_config *next = &core->state.commit_record;
    *next = *c;
    if (!rw_config_commit(next, msg.session_epoch, core->params.value,
                          core->state.key_staged ? core->state.staged_key : NULL)) {
        return refuse(RW_NACK_REASON_OUT_OF_RANGE, (int32_t)(RW_CONFIG_EPOCH_LIMIT - 1u));
    }
    if (!hal->config->request_save(hal->config->ctx, next, sizeof *next)) {
        return refuse(RW_NACK_REASON_STORE_FAILED, 2); /* the store is still busy with another write */
    }
    core->state.commit_pending = true;
    core->state.commit_link = (uint8_t)link;
    core->state.commit_msg_id = frame->msg_id;
    core->state.commit_seq = frame->seq;
    core->state.commit_checksum = frame->checksum;
    return LATER;
}

/* PROVISION_* (USB serial only; the caller checked the link; DISARMED only: the rope is down). Changes are
 * staged in the RAM record and written by PROVISION_COMMIT; the key takes effect at the commit. While a
 * commit is being written, everything but PROVISION_GET is refused NOT_READY (and ARM: cmd_arm). */
static verdict provision(rw_core *core, const rw_hal *hal, rw_link_id link, const rw_frame *frame)
{
    rw_config *c = &core->state.config;
    if (frame->msg_id == RW_MSG_ID_PROVISION_GET) {
        return ACCEPT;
    }
    if (core->state.state != RW_STATE_DISARMED) {
        return refuse(RW_NACK_REASON_BAD_STATE, 0);
    }
    if (core->state.commit_pending) {
        return refuse(RW_NACK_REASON_NOT_READY, 0);
    }
    switch (frame->msg_id) {
    case RW_MSG_ID_PROVISION_SET_WIFI_SSID: {
        rw_msg_provision_set_wifi_ssid msg;
        rw_msg_provision_set_wifi_ssid_unpack(&msg, frame->payload);
        memcpy(c->wifi_ssid, msg.ssid, sizeof c->wifi_ssid);
        break;
    }
    case RW_MSG_ID_PROVISION_SET_WIFI_PASSWORD: {
        rw_msg_provision_set_wifi_password msg;
        rw_msg_provision_set_wifi_password_unpack(&msg, frame->payload);
        size_t n = strlen(msg.password);
        if (n != 0u && n < 8u) {
            return refuse(RW_NACK_REASON_OUT_OF_RANGE, 8); /* WPA2 needs 8..63 characters */
        }
        memcpy(c->wifi_password, msg.password, sizeof c->wifi_password);
        c->password_set = n != 0u ? 1u : 0u;
        break;
    }
    case RW_MSG_ID_PROVISION_SET_KEY: {
        rw_msg_provision_set_key msg;
        rw_msg_provision_set_key_unpack(&msg, frame->payload);
        memcpy(core->state.staged_key, msg.key, RW_KEY_LEN);
        core->state.key_staged = true;
        break;
    }
    case RW_MSG_ID_PROVISION_COMMIT:
        return commit(core, hal, link, frame);
    default:
        return refuse(RW_NACK_REASON_NOT_A_COMMAND, 0);
    }
    core->state.config_dirty = true;
    return ACCEPT;
}

/* PARAM_GET and PARAM_SET are followed by the parameter's value (queued: one datagram per tick). */
static void queue_param_value(rw_core *core, const rw_frame *frame)
{
    uint8_t param_id = frame->payload[0];
    if (param_id >= RW_PARAM_COUNT) {
        return;
    }
    rw_msg_param_value msg = {
        .param_id = param_id, .value = core->params.value[param_id], .param_count = (uint8_t)RW_PARAM_COUNT,
    };
    uint8_t out[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_param_value_encode(&msg, 0u, out, sizeof out); /* numbered when it leaves */
    rw_outbox_push(&core->state.outbox, RW_OUTBOX_REPLY, out, len);
}

/* Over WiFi a frame counts only if it is signed with the key, for this session, with a fresh counter. */
static bool authentic(rw_core *core, const rw_frame *frame)
{
    rw_core_counters *c = &core->state.counters;
    if (core->state.config.key_set == 0u || (frame->flags & RW_FRAME_FLAG_SIGNED) == 0u ||
        !rw_frame_tag_valid(frame, core->state.config.key)) {
        ++c->rx_auth_failed;
        return false;
    }
    if (frame->session_id != rw_core_session_id(core) || frame->counter <= core->state.host_counter) {
        ++c->rx_replayed;
        return false;
    }
    core->state.host_counter = frame->counter;
    return true;
}

bool rw_core_handle_datagram(rw_core *core, const rw_hal *hal, rw_link_id link)
{
    const rw_hal_link *l = link == RW_LINK_SERIAL ? hal->serial : hal->link;
    uint8_t buf[RW_MAX_FRAME_LEN + 1u];
    size_t n = l->recv(l->ctx, buf, sizeof buf);
    if (n == 0u) {
        return false;
    }
    core->state.took_datagram = true;
    rw_frame frame;
    /* A datagram longer than buf arrives truncated to sizeof buf, which is longer than any frame: the
     * decoder refuses it exactly as it refuses the whole datagram (trailing bytes: BAD_LENGTH; a declared
     * payload over the maximum: OVERSIZE; a bad header first: BAD_MAGIC/BAD_VERSION/UNSUPPORTED_FLAGS).
     * A malformed frame is answered with its reason (it carries nothing to authenticate). */
    int result = rw_frame_decode(buf, n > sizeof buf ? sizeof buf : n, &frame);
    if (result != RW_DECODE_OK) {
        ++core->state.counters.rx_bad;
        send_verdict(core, hal, link, frame.msg_id, frame.seq, refuse((uint8_t)result, 0));
        return true;
    }
    const rw_msg_info *info = rw_msg_info_find(frame.msg_id);
    if (info->kind == RW_MSG_KIND_HELLO) {
        ++core->state.counters.rx_ok;
        reply_session_info(core, hal, link, &frame);
        return true;
    }
    if (link == RW_LINK_WIFI && !authentic(core, &frame)) {
        return false; /* dropped and counted: no answer to an unauthenticated sender */
    }
    if (info->kind == RW_MSG_KIND_PROVISION && link != RW_LINK_SERIAL) {
        ++core->state.counters.rx_bad;
        send_verdict(core, hal, link, frame.msg_id, frame.seq, refuse(RW_NACK_REASON_NOT_ON_THIS_LINK, 0));
        return true;
    }
    if (info->kind != RW_MSG_KIND_COMMAND && info->kind != RW_MSG_KIND_HEARTBEAT &&
        info->kind != RW_MSG_KIND_PROVISION) {
        ++core->state.counters.rx_bad;
        send_verdict(core, hal, link, frame.msg_id, frame.seq, refuse(RW_NACK_REASON_NOT_A_COMMAND, 0));
        return true;
    }

    ++core->state.counters.rx_ok;
    l->accept_peer(l->ctx);
    core->state.peer_link = (uint8_t)link;
    core->state.last_host_frame_ms = core->state.uptime_ms;
    core->state.heartbeat_lost = false;
    if (info->kind == RW_MSG_KIND_HEARTBEAT) {
        return false;
    }

    /* the checksum covers header and payload, not the signature: a re-signed retransmission matches */
    const rw_duplicate_entry *dup = rw_duplicate_cache_find(&core->state.duplicates, frame.msg_id, frame.seq,
                                                            frame.checksum, core->state.uptime_ms);
    verdict v;
    if (dup != NULL) {
        ++core->state.counters.rx_duplicates;
        v = refuse(dup->nack_reason, dup->nack_detail);
    } else if (core->state.commit_pending && frame.msg_id == core->state.commit_msg_id &&
               frame.seq == core->state.commit_seq && frame.checksum == core->state.commit_checksum) {
        ++core->state.counters.rx_duplicates; /* the commit being written, again: its answer comes when it is */
        return false;
    } else {
        v = info->kind == RW_MSG_KIND_PROVISION ? provision(core, hal, link, &frame) : execute(core, hal, &frame);
        core->state.last_cmd_seq = frame.seq;
        if (v.later) { /* a commit handed to the store: answered when written, in this tick if it already is */
            return rw_core_provision_poll(core, hal);
        }
        rw_duplicate_cache_store(&core->state.duplicates, frame.msg_id, frame.seq, frame.checksum, v.reason,
                                 v.detail, core->state.uptime_ms);
    }
    send_verdict(core, hal, link, frame.msg_id, frame.seq, v);
    if (v.reason == 0u && (frame.msg_id == RW_MSG_ID_PARAM_GET || frame.msg_id == RW_MSG_ID_PARAM_SET)) {
        queue_param_value(core, &frame);
    }
    if (v.reason == 0u && frame.msg_id == RW_MSG_ID_PROVISION_GET) {
        queue_provision_status(core);
    }
    return true;
}
