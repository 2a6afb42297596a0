/* Burst capture: every control tick's raw readings (encoder count and edge time, the ESC pulse written, the
 * battery reading) into a RAM buffer, then streamed to the host as BURST_DATA frames once the capture ends.
 *
 *   IDLE --rw_burst_start(n)--> CAPTURING --n samples recorded--> STREAMING --last frame taken--> IDLE
 *
 * The buffer holds RW_BURST_MAX_SAMPLES samples of RW_BURST_SAMPLE_LEN (8) bytes: 1000 samples (1 s at the
 * 1 kHz tick) = 8,000 B of the SAMD21's 32 KB RAM, beside the ~8.5 KB the firmware uses without it
 * (bench/bench_firmware_size.py prints both). Recording a sample is a few stores (no division, no float);
 * building a frame copies 6 samples. The capture starts with the tick that accepts the command (its sample is
 * taken after that tick's control step) and never skips a tick;
 * a new burst is refused (BURST_BUSY) until the last frame of the previous one was taken.
 *
 * Portable core module: no Arduino header, no heap, reads no clock (times come in). */
#ifndef RW_BURST_H
#define RW_BURST_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_protocol.h"

#define RW_BURST_MAX_SAMPLES 1000u

typedef enum {
    RW_BURST_IDLE = 0,
    RW_BURST_CAPTURING = 1,
    RW_BURST_STREAMING = 2,
} rw_burst_phase;

typedef struct rw_burst {
    struct {
        rw_burst_sample samples[RW_BURST_MAX_SAMPLES];
        uint16_t count;         /* samples asked for */
        uint16_t captured;      /* samples recorded so far */
        uint16_t streamed;      /* samples handed out in frames so far */
        uint16_t burst_id;      /* the current (or last) burst; counts from 0 since reset */
        uint16_t tick_us;       /* time between samples 0 and 1 (or the tick of sample 0 alone) */
        uint32_t start_time_ms; /* device uptime of sample 0 */
        uint32_t start_time_us; /* uptime of sample 0, microseconds (wraps) */
        uint8_t phase;          /* rw_burst_phase */
        bool started;           /* a burst_id was handed out since reset */
    } state;
} rw_burst;

void rw_burst_reset(rw_burst *b);
/* Begin a capture of `samples` ticks from the next rw_burst_record. Returns 0 (accepted), RW_NACK_REASON_BURST_BUSY
 * (a capture or stream is under way; *detail = samples still to capture plus samples still to stream) or
 * RW_NACK_REASON_OUT_OF_RANGE (samples 0 or over RW_BURST_MAX_SAMPLES; *detail = RW_BURST_MAX_SAMPLES). */
uint8_t rw_burst_start(rw_burst *b, uint16_t samples, int32_t *detail);
static inline bool rw_burst_capturing(const rw_burst *b)
{
    return b->state.phase == RW_BURST_CAPTURING;
}
static inline bool rw_burst_streaming(const rw_burst *b)
{
    return b->state.phase == RW_BURST_STREAMING;
}
/* One control tick's sample (call only while capturing): uptime_ms and uptime_us are the tick's uptime, dt_us
 * the time since the previous tick. The capture ends (streaming begins) with the count'th sample. Inline: it
 * runs every tick of a capture and costs a few stores, no call (bench/bench_tick_instructions.py, part 3). */
static inline void rw_burst_record(rw_burst *b, uint32_t uptime_ms, uint32_t uptime_us, uint32_t dt_us,
                                   const rw_burst_sample *sample)
{
    if (b->state.phase != RW_BURST_CAPTURING) {
        return;
    }
    const uint16_t i = b->state.captured;
    if (i < 2u) {
        const uint32_t tick_us = i == 0u ? dt_us : uptime_us - b->state.start_time_us;
        b->state.tick_us = tick_us > 65535u ? 65535u : (uint16_t)tick_us;
        if (i == 0u) {
            b->state.start_time_ms = uptime_ms;
            b->state.start_time_us = uptime_us;
        }
    }
    b->state.samples[i] = *sample;
    b->state.captured = (uint16_t)(i + 1u);
    if (b->state.captured >= b->state.count) {
        b->state.phase = RW_BURST_STREAMING;
    }
}
/* The next BURST_DATA frame of a finished capture (call only while streaming); the last one returns to IDLE. */
void rw_burst_next_frame(rw_burst *b, rw_msg_burst_data *msg);

#endif /* RW_BURST_H */
