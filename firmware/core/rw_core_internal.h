/* Shared between the core's translation units (rw_core.c, rw_core_commands.c); not for HAL or board code. */
#ifndef RW_CORE_INTERNAL_H
#define RW_CORE_INTERNAL_H

#include "rw_core.h"

void rw_core_apply_params(rw_core *core);
void rw_core_emit_event(rw_core *core, uint8_t event, uint8_t from, uint8_t to, int32_t arg);
void rw_core_set_state(rw_core *core, uint8_t new_state, uint8_t cause);
void rw_core_raise_fault(rw_core *core, uint16_t fault_bit);
/* The load-loss monitor's configuration from the parameters, and its step (speed ticks, after the PI step). */
void rw_core_load_loss_apply_params(rw_core *core);
/* The load-loss check runs in the spindle's 10 ms slot with this dt (the slot's period). */
#define RW_CORE_LOAD_CHECK_DT_S ((float)RW_CORE_SPINDLE_PERIOD_MS * 1.0e-3f)
void rw_core_load_loss_step(rw_core *core);

/* Receive at most one datagram on a link, answer it; returns true when a datagram was sent this tick. */
bool rw_core_handle_datagram(rw_core *core, const rw_hal *hal, rw_link_id link);
/* Send a frame on a link (reply: to the sender of the last datagram; else to that link's peer); frames on
 * WiFi are signed when a key is set. */
/* The seq of a frame about to leave on `link` (a reply now, a queued frame when its signing begins). Each link
 * numbers its own frames, so a host on one link sees no holes for frames sent on the other, and a frame the
 * outbox drops spends no seq. A reply may overtake a queued frame whose signing has begun (by a few ms): the
 * host sees those two out of order, never a hole. */
uint16_t rw_core_take_seq(rw_core *core, rw_link_id link);
void rw_core_link_send(rw_core *core, const rw_hal *hal, rw_link_id link, bool reply, const uint8_t *frame, size_t len);

#endif /* RW_CORE_INTERNAL_H */
