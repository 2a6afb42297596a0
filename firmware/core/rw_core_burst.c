/* Burst streaming (BURST_START, rw_burst.h): a captured burst leaves as BURST_DATA frames, one in the outbox at a
 * time (packed on an other tick with no other job, rw_core.c), behind everything else queued (the outbox's
 * lowest class), so telemetry, events and replies never wait behind it for more than the one frame being
 * signed; its signing begins only when the next telemetry frame is not due before it can finish
 * (rw_core_link.c). Capturing is in the tick (rw_core.c, after the ESC write). */
#include "rw_core_internal.h"

void rw_core_queue_burst_frame(rw_core *core)
{
    rw_outbox *outbox = &core->state.outbox;
    /* never into the last free slots (kept for events and replies): a frame taken from the burst is never lost */
    if (core->state.burst_frame_queued || rw_outbox_free_slots(outbox) < RW_CORE_BURST_FREE_SLOTS) {
        return;
    }
    rw_outbox_slot *slot = rw_outbox_reserve(outbox, RW_OUTBOX_BURST);
    if (slot == NULL) {
        return;
    }
    rw_msg_burst_data msg;
    rw_burst_next_frame(&core->state.burst, &msg);
    /* packed unchecksummed, as telemetry: numbered and checksummed when it leaves (rw_core_link.c) */
    rw_msg_burst_data_pack(&msg, slot->bytes + RW_FRAME_HEADER_LEN);
    const size_t len = rw_core_unnumbered_frame(slot->bytes, RW_MSG_ID_BURST_DATA, RW_MSG_BURST_DATA_LEN);
    core->state.burst_frame_queued = rw_outbox_commit(outbox, slot, RW_OUTBOX_BURST, len);
}
