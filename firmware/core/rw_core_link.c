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
 * doing at most mac_budget units of work (rw_core.h: what the tick's other work leaves of its budget): begin
 * (copy, seq, session id: RW_CORE_MAC_BEGIN_COST), steps (8 bytes of checksum and one MAC block:
 * RW_CORE_MAC_STEP_COST each), finish and send (RW_CORE_MAC_FINISH_COST). Two frames are in the signer at
 * most (state.signers, the older at state.signer_head): while one waits for a tick with room for its finish,
 * the steps of the ticks in between go to the other. Frames finish in the order they began, but a BURST_DATA
 * frame yields to the frame beside it; the counter is taken when a frame leaves, so counters grow in the order
 * frames are sent (seq may not, by up to two frames: the host's gap detector waits for late frames). A frame the
 * signer refuses (not a well-formed frame) is dropped and counted (tx_dropped). */
static uint32_t absorb(rw_signer *signer, uint32_t budget)
{
    if (budget < RW_CORE_MAC_STEP_COST || signer->state.done_blocks >= signer->state.fixed_blocks ||
        !rw_signer_busy(signer)) {
        return 0u; /* no call when no step fits or none is left */
    }
    return RW_CORE_MAC_STEP_COST * (uint32_t)rw_signer_absorb(signer, budget / RW_CORE_MAC_STEP_COST);
}

static bool holds_burst(const rw_signer *s)
{
    return rw_signer_busy(s) && s->state.frame[3] == RW_MSG_ID_BURST_DATA;
}

void rw_core_send_queued(rw_core *core, const rw_hal *hal, bool sent, uint32_t mac_budget)
{
    rw_signer *older = &core->state.signers[core->state.signer_head];
    rw_signer *newer = &core->state.signers[core->state.signer_head ^ 1u];
    const bool signed_link = core->state.peer_link == RW_LINK_WIFI && core->state.config.key_set != 0u;
    if (!signed_link && !rw_signer_busy(older)) {
        const rw_outbox_slot *slot = sent ? NULL : rw_outbox_peek(&core->state.outbox);
        if (slot != NULL) {
            uint8_t frame[RW_MAX_FRAME_LEN];
            memcpy(frame, slot->bytes, slot->len);
            size_t len = rw_frame_renumber(frame, slot->len, rw_core_take_seq(core, (rw_link_id)core->state.peer_link));
            rw_core_link_send(core, hal, (rw_link_id)core->state.peer_link, false, frame, len);
            rw_outbox_pop(&core->state.outbox, slot);
        }
        return;
    }
    if (mac_budget < RW_CORE_MAC_STEP_COST) {
        return; /* nothing of the signing fits this tick */
    }
    /* a BURST_DATA frame yields to the frame signed beside it (telemetry, an event, a reply): that one is served
     * first and may leave first (counters are taken as frames leave, so they still grow in the order sent) */
    rw_signer *first = older;
    rw_signer *second = newer;
    if (rw_signer_busy(newer) && holds_burst(older) && !holds_burst(newer)) {
        first = newer;
        second = older;
    }
    /* 1. the first frame leaves once its steps are done (one a tick); the second only with the first idle */
    rw_signer *done = rw_signer_busy(first) ? (rw_signer_blocks_left(first) == 0u ? first : NULL)
                      : rw_signer_busy(second) && rw_signer_blocks_left(second) == 0u ? second
                                                                                       : NULL;
    if (done != NULL && mac_budget >= RW_CORE_MAC_FINISH_COST && !sent && hal->link != NULL) {
        const uint8_t *frame = NULL;
        size_t len = rw_signer_finish(done, ++core->state.tx_counter, &frame);
        hal->link->send(hal->link->ctx, frame, len);
        mac_budget -= RW_CORE_MAC_FINISH_COST;
        if (done == older) { /* the other one is the older now */
            core->state.signer_head ^= 1u;
            older = newer;
            newer = done;
        }
    }
    /* 2. the next outbox frame into a free signer (the older one when both are idle) */
    rw_signer *free_signer = !rw_signer_busy(older) ? older : (!rw_signer_busy(newer) ? newer : NULL);
    if (free_signer != NULL && signed_link && mac_budget >= RW_CORE_MAC_BEGIN_COST && !sent) {
        const rw_outbox_slot *slot = rw_outbox_peek(&core->state.outbox);
        if (slot != NULL) {
            if (!rw_signer_begin_prepared(free_signer, slot->bytes, slot->len, rw_core_take_seq(core, RW_LINK_WIFI),
                                          rw_core_session_id(core), &core->state.key_mac)) {
                rw_outbox_count_drop(&core->state.outbox); /* counted: its seq is spent */
            }
            rw_outbox_pop(&core->state.outbox, slot);
            mac_budget -= RW_CORE_MAC_BEGIN_COST;
        }
    }
    /* 3. steps with what is left, the first frame first (a frame begun just now is in one of the two; a
     * non-burst frame begun beside a burst frame goes first from the next tick on) */
    mac_budget -= absorb(first, mac_budget);
    (void)absorb(second, mac_budget);
}

void rw_core_link_prepare_key(rw_core *core)
{
    rw_siphash_init(&core->state.key_mac, core->state.config.key);
}

bool rw_core_signing(const rw_core *core)
{
    return rw_signer_busy(&core->state.signers[0]) || rw_signer_busy(&core->state.signers[1]);
}

bool rw_core_signer_free(const rw_core *core)
{
    return !rw_signer_busy(&core->state.signers[0]) || !rw_signer_busy(&core->state.signers[1]);
}

bool rw_core_burst_slot_free(const rw_core *core)
{
    const rw_signer *a = &core->state.signers[0];
    const rw_signer *b = &core->state.signers[1];
    if (rw_signer_busy(a) && rw_signer_busy(b)) {
        return false;
    }
    return !(rw_signer_busy(a) && a->state.frame[3] == RW_MSG_ID_BURST_DATA) &&
           !(rw_signer_busy(b) && b->state.frame[3] == RW_MSG_ID_BURST_DATA);
}
