/* Shared between the core's translation units; not for HAL or board code. The core is split by concept:
 *   rw_core.c             init, the tick and its schedule
 *   rw_core_params.c      parameters into the controllers: every module at boot, a PARAM_SET's modules staged
 *                         to a tick boundary
 *   rw_core_supervisor.c  the state machine and the safety checks (heartbeat, battery, encoder, ToV collapse)
 *   rw_core_commands.c    received frames: decode, authenticate, execute, ACK/NACK
 *   rw_core_spindle.c     the spindle slot: servo reading -> rw_spindle step -> events, state, servo write
 *   rw_core_load_loss.c   the load-loss monitor's use (what the device does when the rope's load vanishes)
 *   rw_core_telemetry.c   the TELEMETRY frame, packed straight into the outbox
 *   rw_core_link.c        sending: per-link seq, signing, the outbox paced over idle ticks
 *   rw_core_boot.c        the first tick: configuration record, session, BOOT
 * and the controllers are modules of their own (rw_speed_loop.h, rw_tov_guard.h, rw_spindle.h, ...). */
#ifndef RW_CORE_INTERNAL_H
#define RW_CORE_INTERNAL_H

#include "rw_core.h"

/* ---- rw_core_params.c ---- */
/* Push the parameter values into every controller's config and prepare them (gains converted once);
 * nothing is left pending. */
void rw_core_apply_params(rw_core *core);
/* The same for the RW_PARAM_MODULE_* bits in modules only (each one in one piece); they are no longer
 * pending. */
void rw_core_prepare_modules(rw_core *core, uint16_t modules);
/* Prepare now those of modules that are pending (before a command that reads them executes). */
void rw_core_params_settle(rw_core *core, uint16_t modules);
/* A module stays pending at most this many ticks that took a datagram; then it is prepared anyway. */
#define RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS 20u
/* The tick's last step: on a tick that took no datagram (state.took_datagram, cleared here), or after
 * RW_CORE_PARAM_APPLY_MAX_WAIT_TICKS ticks that all did, prepare the lowest pending module. */
void rw_core_params_tick_end(rw_core *core);

/* ---- rw_core.c ---- */
void rw_core_emit_event(rw_core *core, uint8_t event, uint8_t from, uint8_t to, int32_t arg);

/* ---- rw_core_supervisor.c ---- */
void rw_core_set_state(rw_core *core, uint8_t new_state, uint8_t cause);
void rw_core_raise_fault(rw_core *core, uint16_t fault_bit);
/* Step 3 of the tick: arming hold, heartbeat, battery, encoder silence, ToV guard and the speed-driven
 * transitions. dt_s/dt_ms: this tick's length; encoder_counts_delta: edges since the estimator's reference
 * (anything but 0 while it is not primed). */
void rw_core_supervise(rw_core *core, float dt_s, uint32_t dt_ms, uint32_t encoder_counts_delta);
/* How the speed loop runs in a device state (OFF for the states that do not drive the rope). */
rw_speed_loop_mode rw_core_speed_loop_mode(uint8_t state);

/* ---- rw_core_spindle.c ---- */
/* The spindle loop, every RW_CORE_SPINDLE_PERIOD_MS: read the servo, step, act on the outcome, write.
 * elapsed_ms: the real time since the previous step (the period, or more after a gap). */
void rw_core_spindle_step(rw_core *core, const rw_hal *hal, uint32_t elapsed_ms);

/* ---- rw_core_load_loss.c ---- */
/* The load-loss monitor's configuration from the parameters (prepared), and its step. */
void rw_core_load_loss_apply_params(rw_core *core);
/* The load-loss check runs in the spindle's 10 ms slot with this dt (the slot's period). */
#define RW_CORE_LOAD_CHECK_DT_S ((float)RW_CORE_SPINDLE_PERIOD_MS * 1.0e-3f)
void rw_core_load_loss_step(rw_core *core);

/* ---- rw_core_commands.c ---- */
/* Receive at most one datagram on a link, answer it; returns true when a datagram was sent this tick. */
bool rw_core_handle_datagram(rw_core *core, const rw_hal *hal, rw_link_id link);
/* A PROVISION_COMMIT whose record the store was writing: once save_status says DONE (or FAILED), the new
 * record (session, key) takes effect and the command is answered ACK (NACK STORE_FAILED); returns true when
 * that answer went out (on the serial link: that link takes no datagram this tick). */
bool rw_core_provision_poll(rw_core *core, const rw_hal *hal);

/* ---- rw_core_telemetry.c ---- */
/* Pack a TELEMETRY frame into the outbox (a full outbox drops it, counted). */
void rw_core_queue_telemetry(rw_core *core, const rw_hal *hal);
/* An unsigned frame of msg_id with a packed payload of payload_len bytes around it, seq 0 and the checksum
 * left 0: what rw_frame_renumber and rw_frame_sign_begin take and complete when it leaves. Its length. */
size_t rw_core_unnumbered_frame(uint8_t *frame, uint8_t msg_id, uint8_t payload_len);
/* round(1000 / telemetry_rate_hz), ms (one float division: from rw_core_apply_params). */
uint32_t rw_core_telemetry_period_ms(const rw_core *core);

/* ---- rw_core_link.c ---- */
/* The seq of a frame about to leave on `link` (a reply now, a queued frame when its signing begins). Each link
 * numbers its own frames, so a host on one link sees no holes for frames sent on the other, and a frame the
 * outbox drops spends no seq. A reply may overtake a queued frame whose signing has begun (by a few ms): the
 * host sees those two out of order, never a hole. */
uint16_t rw_core_take_seq(rw_core *core, rw_link_id link);
/* Send a frame on a link (reply: to the sender of the last datagram; else to that link's peer); frames on
 * WiFi are signed when a key is set. */
void rw_core_link_send(rw_core *core, const rw_hal *hal, rw_link_id link, bool reply, const uint8_t *frame, size_t len);
/* Step 5's send: the next outbox frame to the peer, at most one datagram a tick (none when `sent`: this tick
 * already answered a command); over a keyed WiFi link signed in steps with up to mac_budget units of MAC work
 * (rw_core.h: by the kind of tick). */
void rw_core_send_queued(rw_core *core, const rw_hal *hal, bool sent, uint32_t mac_budget);

/* The MAC's initial state under the link key (state.key_mac), once for every key (boot, PROVISION_COMMIT):
 * beginning a frame then copies it instead of deriving it. */
void rw_core_link_prepare_key(rw_core *core);
/* True while a frame is being signed (either signer busy). */
bool rw_core_signing(const rw_core *core);
/* True when a signer can take the next frame. */
bool rw_core_signer_free(const rw_core *core);
/* True when a signer is free and neither holds a BURST_DATA frame: the next burst frame may be queued. */
bool rw_core_burst_slot_free(const rw_core *core);

/* ---- rw_core_boot.c ---- */
/* First tick: the stored configuration (key, parameters) and a new session, then the BOOT event. */
void rw_core_boot(rw_core *core, const rw_hal *hal);

/* The next BURST_DATA frame of a captured burst into the outbox, when it is empty and rw_core_burst_slot_free
 * (rw_core_burst.c): a TELEMETRY frame packed after it waits for it alone (it begins in the other signer); true
 * when one was packed. */
bool rw_core_queue_burst_frame(rw_core *core);

#endif /* RW_CORE_INTERNAL_H */
