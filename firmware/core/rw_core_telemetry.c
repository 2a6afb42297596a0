/* Telemetry: the TELEMETRY frame at telemetry_rate_hz (step 5 of rw_core_tick, on an "other" tick of the
 * schedule), packed straight into its outbox slot. The frame leaves later, through rw_core_link.c, which
 * numbers it for its link and computes its checksum then (rw_frame_renumber, rw_frame_sign_begin): so it is
 * not checksummed here (a CRC over 60 bytes is ~1,000 M0+ cycles, and was done twice). Every float is turned
 * into wire units by bit operations (rw_wire_units.h), no soft-float call. */
#include <string.h>

#include "rw_core_internal.h"
#include "rw_wire_units.h"

static uint8_t spindle_flags(const rw_spindle *sp)
{
    uint8_t flags = 0u;
    flags |= sp->state.homed ? RW_SPINDLE_FLAG_HOMED : 0u;
    flags |= sp->state.answering ? RW_SPINDLE_FLAG_ANSWERING : 0u;
    flags |= sp->state.turns.state.dead_reckoning ? RW_SPINDLE_FLAG_DEAD_ZONE : 0u;
    flags |= sp->state.moving_speed_raw != 0u ? RW_SPINDLE_FLAG_MOVING : 0u;
    flags |= sp->state.mode == RW_SPINDLE_HOMING ? RW_SPINDLE_FLAG_HOMING : 0u;
    return flags;
}

size_t rw_core_unnumbered_frame(uint8_t *frame, uint8_t msg_id, uint8_t payload_len)
{
    frame[0] = RW_PROTOCOL_MAGIC;
    frame[1] = RW_PROTOCOL_VERSION;
    frame[2] = 0u; /* flags: unsigned */
    frame[3] = msg_id;
    frame[4] = 0u; /* seq: numbered when it leaves */
    frame[5] = 0u;
    frame[6] = payload_len;
    memset(frame + RW_FRAME_HEADER_LEN + payload_len, 0, RW_FRAME_CHECKSUM_LEN);
    return RW_FRAME_HEADER_LEN + (size_t)payload_len + RW_FRAME_CHECKSUM_LEN;
}

void rw_core_queue_telemetry(rw_core *core, const rw_hal *hal)
{
    const rw_core_counters *c = &core->state.counters;
    uint32_t age_ms = core->state.uptime_ms - core->state.last_host_frame_ms;
    rw_msg_telemetry msg = {
        .time_ms = core->state.uptime_ms,
        .state = core->state.state,
        .fault_bits = core->state.fault_bits,
        .rope_speed_target_mmps = rw_wire_u16_times(core->state.target_mps, 125u, 3), /* x 1000 */
        .rope_speed_setpoint_mmps = rw_wire_u16_times(rw_speed_loop_setpoint_mps(&core->state.loop), 125u, 3),
        .rope_speed_mmps = rw_wire_u16_times(core->state.measured_mps, 125u, 3),
        .motor_rpm = rw_wire_u16_times(rw_mt_speed_estimator_rev_per_s(&core->state.loop.estimator), 15u, 2), /* x 60 */
        .esc_pulse_us = core->state.pulse_us,
        .battery_mv = core->state.battery_mv,
        .heartbeat_age_ms = age_ms > 65535u ? 65535u : (uint16_t)age_ms,
        .rx_ok = c->rx_ok,
        .rx_bad = c->rx_bad,
        .rx_duplicates = c->rx_duplicates,
        .nacks = c->nacks,
        .events = c->events,
        .tick_overruns = hal->scheduler != NULL ? (uint16_t)hal->scheduler->tick_overruns(hal->scheduler->ctx) : 0u,
        .guide_position_um = core->state.spindle.state.position_um,
        .guide_target_um = rw_wire_i32_times(core->state.spindle.state.target_mm, 125u, 3),
        .spindle_load_permille = core->state.spindle.state.load_permille,
        .spindle_flags = spindle_flags(&core->state.spindle),
        .spindle_rejected = core->state.spindle.state.turns.state.rejected,
        .rx_auth_failed = c->rx_auth_failed,
        .rx_replayed = c->rx_replayed,
        .tx_dropped = rw_outbox_dropped(&core->state.outbox),
        .esc_pulse_third_us = core->state.pulse_third_us,
        .spindle_moving_speed_raw = core->state.spindle.state.moving_speed_raw,
        .encoder_counts = core->state.encoder_counts,
        .encoder_edge_us = core->state.encoder_edge_us,
    };
    /* packed straight into its outbox slot (no copy); a full outbox drops it (counted), as a push would */
    rw_outbox_slot *slot = rw_outbox_reserve(&core->state.outbox, RW_OUTBOX_TELEMETRY);
    if (slot != NULL) {
        rw_msg_telemetry_pack(&msg, slot->bytes + RW_FRAME_HEADER_LEN);
        const size_t len = rw_core_unnumbered_frame(slot->bytes, RW_MSG_ID_TELEMETRY, RW_MSG_TELEMETRY_LEN);
        rw_outbox_commit(&core->state.outbox, slot, RW_OUTBOX_TELEMETRY, len);
    }
}

uint32_t rw_core_telemetry_period_ms(const rw_core *core)
{
    const float rate_hz = rw_params_get(&core->params, RW_PARAM_TELEMETRY_RATE_HZ);
    return (uint32_t)(1000.0f / rate_hz + 0.5f); /* the parameter's range (> 0) keeps this finite */
}
