/* Burst streaming (BURST_START, rw_burst.h): a captured burst leaves as BURST_DATA frames, one at a time, only
 * into an empty outbox with a signer free and no other BURST_DATA frame being signed, so telemetry, events and
 * replies never wait behind it for more than one frame (they begin in the other signer), and the burst takes
 * every signing slot they leave. Capturing is in the tick (rw_core.c, after the ESC write). */
#include "rw_core_internal.h"

bool rw_core_queue_burst_frame(rw_core *core)
{
    if (!rw_core_burst_slot_free(core) || rw_outbox_peek(&core->state.outbox) != NULL) {
        return false;
    }
    rw_msg_burst_data msg;
    rw_burst_next_frame(&core->state.burst, &msg);
    rw_outbox_slot *slot = rw_outbox_reserve(&core->state.outbox, RW_OUTBOX_BURST);
    if (slot != NULL) {
        /* packed unchecksummed, as telemetry: numbered and checksummed when it leaves (rw_core_link.c) */
        rw_msg_burst_data_pack(&msg, slot->bytes + RW_FRAME_HEADER_LEN);
        const size_t len = rw_core_unnumbered_frame(slot->bytes, RW_MSG_ID_BURST_DATA, RW_MSG_BURST_DATA_LEN);
        rw_outbox_commit(&core->state.outbox, slot, RW_OUTBOX_BURST, len);
    }
    return true;
}
