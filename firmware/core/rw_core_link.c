/* Sending: each link numbers its own frames (rw_core_take_seq); over a keyed WiFi link every frame is signed
 * (SipHash-2-4 for the session, with the device's own counter): a reply at once (rw_core_link_send), a queued
 * frame in steps over idle ticks (rw_core_send_queued), so that no periodic tick carries a whole MAC. */
#include <string.h>

#include "rw_core_internal.h"

static const rw_hal_link *link_of(const rw_hal *hal, rw_link_id link)
{
    return link == RW_LINK_SERIAL ? hal->serial : (link == RW_LINK_WIFI ? hal->link : NULL);
}

uint16_t rw_core_take_seq(rw_core *core, rw_link_id link)
{
    return core->state.tx_seq[link == RW_LINK_SERIAL ? 1 : 0]++;
}

void rw_core_link_send(rw_core *core, const rw_hal *hal, rw_link_id link, bool reply, const uint8_t *frame, size_t len)
{
    const rw_hal_link *l = link_of(hal, link);
    if (l == NULL || len == 0u) {
        return;
    }
    if (link == RW_LINK_WIFI && core->state.config.key_set != 0u) {
        uint8_t signed_frame[RW_MAX_FRAME_LEN];
        memcpy(signed_frame, frame, len);
        len = rw_frame_sign(signed_frame, len, sizeof signed_frame, rw_core_session_id(core), ++core->state.tx_counter,
                            core->state.config.key);
        if (len == 0u) {
            return;
        }
        (reply ? l->reply : l->send)(l->ctx, signed_frame, len);
        return;
    }
    (reply ? l->reply : l->send)(l->ctx, frame, len);
}

/* Whether the signer may take a BURST_DATA frame now: only when the next telemetry frame is not due before the
 * burst frame's signing can end (RW_CORE_BURST_SIGN_MS), so that a telemetry frame never waits behind one. */
static bool burst_may_begin(const rw_core *core)
{
    const int32_t to_telemetry_ms = (int32_t)(core->state.telemetry_due_ms - core->state.uptime_ms);
    return to_telemetry_ms > (int32_t)RW_CORE_BURST_SIGN_MS;
}

/* Step 5's send: the next outbox frame goes to the peer, at most one datagram a tick (none when this tick
 * already answered a command). Over a keyed WiFi link it is signed first, in steps (rw_signer.h), each tick
 * doing what is left of its work budget (rw_core.h): load (RW_CORE_MAC_LOAD_COST), checksum (RW_CORE_MAC_CRC_CHUNK_COST a
 * chunk), absorb (RW_CORE_MAC_ABSORB_CALL_COST a call,
 * RW_CORE_MAC_BLOCK_COST a block), seal (counter, last block, tag:
 * RW_CORE_MAC_SEAL_*_COST), send (RW_CORE_MAC_SEND_COST). So no tick
 * carries a whole MAC. The counter is the next one when the frame is sealed; a frame sealed and not yet sent
 * when something else took a counter (an ACK) is sealed again. A frame the signer refuses (not a well-formed
 * frame) is dropped and counted (tx_dropped). */
void rw_core_send_queued(rw_core *core, const rw_hal *hal, bool sent, uint32_t budget)
{
    rw_signer *signer = &core->state.signer;
    const bool signed_link = core->state.peer_link == RW_LINK_WIFI && core->state.config.key_set != 0u;
    const bool busy = rw_signer_busy(signer);
    if (signed_link && (busy ? budget == 0u : budget < RW_CORE_MAC_LOAD_COST)) {
        return; /* no signing step fits this tick: not even a look into the outbox */
    }
    if (!busy) {
        const rw_outbox_slot *slot = sent ? NULL : rw_outbox_peek(&core->state.outbox);
        if (slot == NULL) {
            return;
        }
        const bool burst = slot->cls == RW_OUTBOX_BURST;
        if (!signed_link) {
            uint8_t frame[RW_MAX_FRAME_LEN];
            memcpy(frame, slot->bytes, slot->len);
            size_t len = rw_frame_renumber(frame, slot->len, rw_core_take_seq(core, (rw_link_id)core->state.peer_link));
            rw_core_link_send(core, hal, (rw_link_id)core->state.peer_link, false, frame, len);
            rw_outbox_pop(&core->state.outbox, slot);
            core->state.burst_frame_queued = core->state.burst_frame_queued && !burst;
            return;
        }
        if (burst && !burst_may_begin(core)) {
            return;
        }
        if (!rw_signer_load(signer, slot->bytes, slot->len, rw_core_take_seq(core, RW_LINK_WIFI),
                            rw_core_session_id(core), core->state.config.key)) {
            rw_outbox_count_drop(&core->state.outbox); /* counted: its seq is spent */
        }
        rw_outbox_pop(&core->state.outbox, slot);
        core->state.burst_frame_queued = core->state.burst_frame_queued && !burst;
        budget -= RW_CORE_MAC_LOAD_COST;
        if (!rw_signer_busy(signer)) {
            return;
        }
    }
    budget -= RW_CORE_MAC_CRC_CHUNK_COST * (uint32_t)rw_signer_checksum(signer, budget / RW_CORE_MAC_CRC_CHUNK_COST);
    if (budget >= RW_CORE_MAC_ABSORB_CALL_COST + RW_CORE_MAC_BLOCK_COST && rw_signer_blocks_left(signer) != 0u) {
        const size_t n = rw_signer_absorb(signer, (budget - RW_CORE_MAC_ABSORB_CALL_COST) / RW_CORE_MAC_BLOCK_COST);
        budget -= n == 0u ? 0u : RW_CORE_MAC_ABSORB_CALL_COST + RW_CORE_MAC_BLOCK_COST * (uint32_t)n;
    }
    /* the counter the frame gets if it is sent before anything else is signed; sealed again if not */
    const uint64_t next_counter = core->state.tx_counter + 1u;
    const bool counter_current = (rw_signer_sealing(signer) || rw_signer_sealed(signer)) &&
                                 rw_signer_sealed_counter(signer) == next_counter;
    if (!counter_current && budget >= RW_CORE_MAC_SEAL_COUNTER_COST && rw_signer_seal_counter(signer, next_counter)) {
        budget -= RW_CORE_MAC_SEAL_COUNTER_COST;
    }
    if (rw_signer_sealing(signer) && !rw_signer_last_absorbed(signer) && budget >= RW_CORE_MAC_SEAL_LAST_COST &&
        rw_signer_seal_last(signer)) {
        budget -= RW_CORE_MAC_SEAL_LAST_COST;
    }
    if (rw_signer_last_absorbed(signer) && budget >= RW_CORE_MAC_SEAL_TAG_COST && rw_signer_seal_tag(signer)) {
        budget -= RW_CORE_MAC_SEAL_TAG_COST;
    }
    if (rw_signer_sealed(signer) && rw_signer_sealed_counter(signer) == next_counter && budget >= RW_CORE_MAC_SEND_COST &&
        !sent && hal->link != NULL) {
        const uint8_t *frame = NULL;
        const size_t len = rw_signer_sealed_frame(signer, &frame);
        core->state.tx_counter = next_counter;
        hal->link->send(hal->link->ctx, frame, len);
        rw_signer_sent(signer);
    }
}
