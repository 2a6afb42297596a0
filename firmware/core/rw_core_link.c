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

/* Step 5's send: the next outbox frame goes to the peer, at most one datagram a tick (none when this tick
 * already answered a command). Over a keyed WiFi link it is signed first, in steps (rw_signer.h), each tick
 * doing at most mac_budget blocks' worth of work (rw_core.h): begin (copy, checksum: RW_CORE_MAC_BEGIN_COST),
 * absorb (one per block), finish and send (RW_CORE_MAC_FINISH_COST). So no tick carries a whole MAC, and a
 * telemetry frame leaves within two idle ticks. Its counter is taken when it
 * leaves. A frame the signer refuses (not a well-formed frame) is dropped and counted (tx_dropped). */
void rw_core_send_queued(rw_core *core, const rw_hal *hal, bool sent, uint32_t mac_budget)
{
    rw_signer *signer = &core->state.signer;
    const bool signed_link = core->state.peer_link == RW_LINK_WIFI && core->state.config.key_set != 0u;
    const bool busy = rw_signer_busy(signer);
    if (signed_link && (busy ? mac_budget == 0u : mac_budget < RW_CORE_MAC_BEGIN_COST)) {
        return; /* no signing step fits this tick: not even a look into the outbox */
    }
    if (!busy) {
        const rw_outbox_slot *slot = sent ? NULL : rw_outbox_peek(&core->state.outbox);
        if (slot == NULL) {
            return;
        }
        if (!signed_link) {
            uint8_t frame[RW_MAX_FRAME_LEN];
            memcpy(frame, slot->bytes, slot->len);
            size_t len = rw_frame_renumber(frame, slot->len, rw_core_take_seq(core, (rw_link_id)core->state.peer_link));
            rw_core_link_send(core, hal, (rw_link_id)core->state.peer_link, false, frame, len);
            rw_outbox_pop(&core->state.outbox, slot);
            return;
        }
        if (!rw_signer_begin(signer, slot->bytes, slot->len, rw_core_take_seq(core, RW_LINK_WIFI),
                             rw_core_session_id(core), core->state.config.key)) {
            rw_outbox_count_drop(&core->state.outbox); /* counted: its seq is spent */
        }
        rw_outbox_pop(&core->state.outbox, slot);
        (void)rw_signer_absorb(signer, mac_budget - RW_CORE_MAC_BEGIN_COST);
        return;
    }
    if (mac_budget == 0u) {
        return;
    }
    const size_t now = rw_signer_absorb(signer, mac_budget);
    if (rw_signer_blocks_left(signer) == 0u && now + RW_CORE_MAC_FINISH_COST <= mac_budget && !sent &&
        hal->link != NULL) {
        const uint8_t *frame = NULL;
        size_t len = rw_signer_finish(signer, ++core->state.tx_counter, &frame);
        hal->link->send(hal->link->ctx, frame, len);
    }
}
