/* The core's top level: initialisation and the tick with its schedule (rw_core.h). The concepts the tick calls live in their own files
 * (rw_core_internal.h lists them). */
#include "rw_core.h"

#include <stddef.h>
#include <string.h>

#include "rw_core_internal.h"
#include "rw_float_bits.h"

/* A tick longer than this (a debugger pause, a stalled loop) is integrated as this long, so the PI and
 * ramp never take one giant step; the uptime still advances by the real time. */
#define RW_CORE_MAX_CONTROL_DT_S 0.05f
/* The tick and the speed step (every other tick) at the nominal period, seconds: what the controllers are
 * prepared for. */
#define RW_CORE_TICK_S ((float)RW_CORE_TICK_US * 1.0e-6f)
#define RW_CORE_SPEED_DT_US (2u * RW_CORE_TICK_US)
#define RW_CORE_SPEED_DT_S ((float)RW_CORE_SPEED_DT_US * 1.0e-6f)

/* dt_us in seconds, capped at RW_CORE_MAX_CONTROL_DT_S: the nominal period is a constant, any other is
 * converted (a conversion and a multiply, ~200 M0+ instructions). */
static float capped_dt_s(uint32_t dt_us, uint32_t nominal_us, float nominal_s)
{
    if (dt_us == nominal_us) {
        return nominal_s;
    }
    const float dt_s = (float)dt_us * 1.0e-6f;
    return dt_s > RW_CORE_MAX_CONTROL_DT_S ? RW_CORE_MAX_CONTROL_DT_S : dt_s;
}

void rw_core_init(rw_core *core)
{
    memset(core, 0, sizeof *core);
    rw_params_init_defaults(&core->params);
    rw_speed_loop_init(&core->state.loop);
    rw_tov_guard_config guard;
    rw_tov_guard_config_defaults(&guard);
    rw_tov_guard_init(&core->state.guard, &guard);
    rw_duplicate_cache_reset(&core->state.duplicates);
    rw_outbox_reset(&core->state.outbox);
    rw_signer_reset(&core->state.signers[0]);
    rw_signer_reset(&core->state.signers[1]);
    rw_spindle_config spindle = { 0 };
    rw_spindle_init(&core->state.spindle, &spindle);
    rw_load_monitor_config load_monitor;
    rw_load_monitor_config_defaults(&load_monitor);
    rw_load_monitor_init(&core->state.load_monitor, &load_monitor);
    rw_core_apply_params(core);
    core->state.state = RW_STATE_DISARMED;
    core->state.peer_link = RW_LINK_WIFI; /* until a host is heard, the WiFi HAL drops what has no peer */
    core->state.pulse_us = (uint16_t)rw_params_get(&core->params, RW_PARAM_ESC_MIN_US);
    core->state.pulse_third_us = (uint16_t)(3u * core->state.pulse_us);
    rw_burst_reset(&core->state.burst);
}

/* Bindings hand rw_config_set_params the core's address for its parameter values. */
_Static_assert(offsetof(rw_core, params) == 0, "rw_core.params must stay the first member");

bool rw_core_tx_idle(const rw_core *core)
{
    return rw_outbox_peek(&core->state.outbox) == NULL && !rw_core_signing(core);
}

size_t rw_core_sizeof(void)
{
    return sizeof(rw_core);
}

void rw_core_emit_event(rw_core *core, uint8_t event, uint8_t from, uint8_t to, int32_t arg)
{
    rw_msg_event msg = {
        .time_ms = core->state.uptime_ms,
        .event_seq = ++core->state.counters.events,
        .event = event,
        .state_from = from,
        .state_to = to,
        .arg = arg,
    };
    uint8_t frame[RW_MAX_FRAME_LEN];
    size_t len = rw_msg_event_encode(&msg, 0u, frame, sizeof frame); /* numbered when it leaves */
    rw_outbox_push(&core->state.outbox, RW_OUTBOX_EVENT, frame, len);
}

/* The periodic job of an "other" tick (the schedule, rw_core.h), at most one a tick, in this order. */
typedef enum {
    RW_CORE_JOB_NONE = 0,   /* an idle tick: the signing of queued frames advances */
    RW_CORE_JOB_TELEMETRY,  /* pack a TELEMETRY frame */
    RW_CORE_JOB_SPINDLE,    /* the spindle loop and the load-loss check */
    RW_CORE_JOB_BATTERY,    /* the feed-forward's battery factor (one division) for a changed reading, and
                               signing with what is left of the budget */
} rw_core_job;

static bool due(uint32_t now_ms, uint32_t due_ms)
{
    return (int32_t)(now_ms - due_ms) >= 0;
}

static rw_core_job other_tick_job(const rw_core *core)
{
    const uint32_t now_ms = core->state.uptime_ms;
    if (due(now_ms, core->state.telemetry_due_ms)) {
        return RW_CORE_JOB_TELEMETRY;
    }
    if (due(now_ms, core->state.spindle_due_ms)) {
        return RW_CORE_JOB_SPINDLE;
    }
    if (due(now_ms, core->state.battery_due_ms) &&
        !rw_f32_same(core->state.battery_v, rw_speed_loop_battery_v(&core->state.loop))) {
        return RW_CORE_JOB_BATTERY;
    }
    return RW_CORE_JOB_NONE;
}

void rw_core_tick(rw_core *core, const rw_hal *hal, uint32_t now_us)
{
    if (!core->state.started) {
        core->state.started = true;
        core->state.last_now_us = now_us;
        rw_core_boot(core, hal);
    }
    uint32_t dt_us = now_us - core->state.last_now_us;
    core->state.last_now_us = now_us;
    uint32_t total_us = core->state.uptime_rem_us + dt_us;
    uint32_t dt_ms;
    if (total_us < 2000u && total_us >= dt_us) { /* the usual tick: no division (same result) */
        dt_ms = total_us >= 1000u ? 1u : 0u;
        total_us -= dt_ms * 1000u;
    } else {
        dt_ms = total_us / 1000u;
        total_us %= 1000u;
    }
    core->state.uptime_ms += dt_ms;
    core->state.uptime_rem_us = total_us;
    const float dt_s = capped_dt_s(dt_us, RW_CORE_TICK_US, RW_CORE_TICK_S);
    /* the schedule (rw_core.h): speed ticks and other ticks alternate */
    const bool speed_tick = core->state.speed_tick_next;
    core->state.speed_tick_next = !speed_tick;
    uint32_t speed_dt_us = core->state.speed_dt_us + dt_us;
    core->state.speed_dt_us = speed_dt_us < dt_us ? UINT32_MAX : speed_dt_us; /* saturates */
    rw_speed_loop *loop = &core->state.loop;

    /* 1. sensors: the encoder every tick (supervision watches its count), the estimator on speed ticks */
    rw_encoder_sample enc = hal->encoder->read(hal->encoder->ctx);
    /* for TELEMETRY and bursts: edges since boot and the latest edge's time on the uptime clock (us), so what
     * the host sees does not depend on where the HAL's counters and tick clock started */
    if (!core->state.encoder_origin_set) {
        core->state.encoder_origin_set = true;
        core->state.encoder_boot_counts = enc.counts;
    }
    const uint32_t uptime_us = core->state.uptime_ms * 1000u + core->state.uptime_rem_us;
    core->state.encoder_counts = enc.counts - core->state.encoder_boot_counts;
    core->state.encoder_edge_us = uptime_us - (now_us - enc.last_edge_us);
    uint32_t counts_delta = enc.counts - loop->estimator.state.last_count;
    bool primed = loop->estimator.state.primed;
    float speed_dt_s = 0.0f;
    if (speed_tick) {
        speed_dt_s = capped_dt_s(core->state.speed_dt_us, RW_CORE_SPEED_DT_US, RW_CORE_SPEED_DT_S);
        core->state.speed_dt_us = 0u;
        core->state.measured_mps = rw_speed_loop_measure(loop, enc.counts, enc.last_edge_us, now_us, speed_dt_s);
    }
    uint16_t battery_mv = hal->battery->read_mv(hal->battery->ctx);
    if (battery_mv != core->state.battery_mv) { /* volts only when the reading changes */
        core->state.battery_mv = battery_mv;
        core->state.battery_v = (float)battery_mv * 1.0e-3f;
    }

    /* 2. at most one received datagram per link (USB serial first: it is where provisioning happens) */
    bool sent = rw_core_provision_poll(core, hal); /* a PROVISION_COMMIT's write done: its answer, on serial */
    sent = (!sent && hal->serial != NULL && rw_core_handle_datagram(core, hal, RW_LINK_SERIAL)) || sent;
    sent = rw_core_handle_datagram(core, hal, RW_LINK_WIFI) || sent;

    /* 3. supervision; the periodic jobs only on other ticks, one job a tick */
    rw_core_supervise(core, dt_s, dt_ms, primed ? counts_delta : 1u);
    const rw_core_job job = speed_tick ? RW_CORE_JOB_NONE : other_tick_job(core);
    switch (job) {
    case RW_CORE_JOB_SPINDLE: {
        /* the real time since the last spindle step: after a tick gap the dead reckoning must cover it */
        uint32_t elapsed_ms = core->state.uptime_ms - core->state.spindle_last_ms;
        if (elapsed_ms == 0u || elapsed_ms > 60000u) {
            elapsed_ms = RW_CORE_SPINDLE_PERIOD_MS; /* first step */
        }
        rw_core_spindle_step(core, hal, elapsed_ms);
        /* the load-loss check shares the 10 ms slot (its time constants are 50 ms and more; it reads the PI's
         * integral, which the speed ticks keep current). Its dt is the slot's period: the slot keeps it but
         * when a telemetry tick holds it back once (2 ms), and a constant dt keeps the filters' coefficients
         * prepared (a float division each). */
        rw_core_load_loss_step(core);
        core->state.spindle_last_ms = core->state.uptime_ms;
        core->state.spindle_due_ms = core->state.uptime_ms + RW_CORE_SPINDLE_PERIOD_MS;
        break;
    }
    case RW_CORE_JOB_BATTERY:
        /* the feed-forward's battery division happens here, never on a speed tick (it sees the battery a few
         * ms late) */
        rw_speed_loop_set_battery(loop, core->state.battery_v);
        /* at most once a period: a reading that changes every tick (ADC noise) would take every idle tick from
         * the signing */
        core->state.battery_due_ms = core->state.uptime_ms + RW_CORE_BATTERY_PERIOD_MS;
        break;
    case RW_CORE_JOB_TELEMETRY:
    case RW_CORE_JOB_NONE:
        break;
    }

    /* 4. control: the speed step on speed ticks; a state that stops driving the rope sets the ESC minimum at
     * once, on any tick */
    const rw_speed_loop_mode mode = rw_core_speed_loop_mode(core->state.state);
    if (mode == RW_SPEED_LOOP_OFF) {
        rw_speed_loop_reset(loop);
    } else if (speed_tick) {
        (void)rw_speed_loop_step(loop, mode, core->state.target_mps, now_us, speed_dt_s);
    }
    core->state.pulse_us = rw_speed_loop_pulse_us(loop);
    if (hal->esc->write_pulse_third_us != NULL) { /* the timer's resolution (TCC1: 1/3 us) */
        core->state.pulse_third_us = rw_speed_loop_pulse_third_us(loop);
        hal->esc->write_pulse_third_us(hal->esc->ctx, core->state.pulse_third_us);
    } else { /* whole microseconds only: that is the pulse the ESCs get */
        core->state.pulse_third_us = (uint16_t)(3u * core->state.pulse_us);
        hal->esc->write_pulse_us(hal->esc->ctx, core->state.pulse_us);
    }
    if (rw_burst_capturing(&core->state.burst)) {
        const rw_burst_sample sample = { .encoder_counts = (uint16_t)core->state.encoder_counts,
                                         .encoder_edge_us = (uint16_t)core->state.encoder_edge_us,
                                         .esc_pulse_third_us = core->state.pulse_third_us,
                                         .battery_mv = battery_mv };
        rw_burst_record(&core->state.burst, core->state.uptime_ms, uptime_us, dt_us, &sample);
    }

    /* 5. telemetry, then at most one datagram out per tick */
    if (job == RW_CORE_JOB_TELEMETRY) {
        rw_core_queue_telemetry(core, hal);
        /* held back by the schedule (<= 2 ms): the next frame is due one period after this one was */
        uint32_t late_ms = core->state.uptime_ms - core->state.telemetry_due_ms;
        late_ms = late_ms <= RW_CORE_SCHEDULE_MAX_HOLD_MS ? late_ms : 0u;
        core->state.telemetry_due_ms = core->state.uptime_ms + core->state.telemetry_period_ms - late_ms;
    }
    /* signing (rw_core_link.c): each kind of tick does what its own work leaves room for (rw_core.h) */
    uint32_t mac_budget = RW_CORE_MAC_STEP_BUDGET; /* telemetry ticks: one step */
    if (speed_tick) {
        mac_budget = RW_CORE_MAC_STEP_BUDGET;
    } else if (job == RW_CORE_JOB_SPINDLE) {
        mac_budget = 0u; /* the spindle step and the load-loss check fill it */
    } else if (job == RW_CORE_JOB_NONE) {
        mac_budget = RW_CORE_MAC_TICK_BUDGET;
    } else if (job == RW_CORE_JOB_BATTERY) {
        mac_budget = RW_CORE_MAC_TICK_BUDGET - RW_CORE_MAC_BATTERY_COST;
    } else if (job == RW_CORE_JOB_TELEMETRY && rw_core_signer_free(core)) {
        mac_budget = RW_CORE_MAC_BEGIN_COST; /* the frame just packed begins at once */
    }
    if ((job == RW_CORE_JOB_NONE || job == RW_CORE_JOB_BATTERY) && !speed_tick &&
        rw_burst_streaming(&core->state.burst) && rw_core_queue_burst_frame(core)) {
        /* this tick's work is the burst frame's pack and its begin (as a telemetry tick's is; a signer is free),
         * with at most the battery division beside it */
        mac_budget = job == RW_CORE_JOB_NONE ? RW_CORE_MAC_BEGIN_COST : 0u;
    }
    rw_core_send_queued(core, hal, sent, mac_budget);
    /* 6. a staged parameter change: one module's conversion, at the tick boundary (rw_core_params.c) */
    rw_core_params_tick_end(core);
}
