#include "rw_burst.h"

#include <string.h>

void rw_burst_reset(rw_burst *b)
{
    memset(&b->state, 0, sizeof b->state);
}

uint8_t rw_burst_start(rw_burst *b, uint16_t samples, int32_t *detail)
{
    if (b->state.phase != RW_BURST_IDLE) {
        *detail = (int32_t)(b->state.count - b->state.captured) + (int32_t)(b->state.captured - b->state.streamed);
        return RW_NACK_REASON_BURST_BUSY;
    }
    if (samples == 0u || samples > RW_BURST_MAX_SAMPLES) {
        *detail = (int32_t)RW_BURST_MAX_SAMPLES;
        return RW_NACK_REASON_OUT_OF_RANGE;
    }
    b->state.burst_id = b->state.started ? (uint16_t)(b->state.burst_id + 1u) : 0u;
    b->state.started = true;
    b->state.count = samples;
    b->state.captured = 0u;
    b->state.streamed = 0u;
    b->state.phase = RW_BURST_CAPTURING;
    *detail = 0;
    return 0u;
}

void rw_burst_next_frame(rw_burst *b, rw_msg_burst_data *msg)
{
    memset(msg, 0, sizeof *msg);
    msg->burst_id = b->state.burst_id;
    msg->start_time_ms = b->state.start_time_ms;
    msg->start_time_us = b->state.start_time_us;
    msg->tick_us = b->state.tick_us;
    msg->sample_count = b->state.count;
    msg->first_sample = b->state.streamed;
    if (b->state.phase != RW_BURST_STREAMING) {
        return;
    }
    unsigned n = (unsigned)(b->state.count - b->state.streamed);
    n = n < RW_BURST_SAMPLES_PER_FRAME ? n : RW_BURST_SAMPLES_PER_FRAME;
    for (unsigned k = 0u; k < n; ++k) {
        rw_burst_sample_put(msg->samples, k, &b->state.samples[b->state.streamed + k]);
    }
    b->state.streamed = (uint16_t)(b->state.streamed + n);
    if (b->state.streamed >= b->state.count) {
        b->state.phase = RW_BURST_IDLE;
    }
}
