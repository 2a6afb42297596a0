/* Encoder capture: an interrupt on every rising edge of D7 counts it and stores micros().
 *
 * Why an interrupt with micros() and not a timer/event-system capture: 64 counts/rev at 1,650-15,000 rpm
 * is 1.8-16 kHz of edges (62.5 us apart at the top). The EIC handler (Arduino's attachInterrupt dispatch,
 * about 1 us) plus this handler (a counter increment and micros(), which reads SysTick and the millisecond
 * counter: about 1 us) costs about 2-3 us per edge, 3-5 % of the CPU at 16 kHz - affordable. The M/T
 * estimator in the core divides the edges of a tick by the time between the first and last captured edge,
 * so the error is the capture jitter (interrupt latency, at most a few microseconds when another handler
 * is running) over that span: under 0.5 % at 1 ms, and the core's low-pass filters it further. micros()
 * is the same clock the control tick uses (rw_arduino_encoder_latch), so both timestamps agree by design.
 * A timer capture (EIC event -> EVSYS -> TC capture, plus a second TC counting the events) would remove
 * the per-edge interrupt and its jitter; it costs two more timers and event channels and is the upgrade
 * if the tick budget gets tight (docs/board.md).
 *
 * The count and time are written only by the handler and read together with interrupts masked. */
#include "arduino_encoder.h"

#include <Arduino.h>

#include "arduino_board.h"

namespace {

volatile uint32_t edge_count = 0u;
volatile uint32_t last_edge_us = 0u;

void on_encoder_edge()
{
    last_edge_us = micros();
    edge_count = edge_count + 1u;
}

rw_encoder_sample read_encoder(void *ctx)
{
    return static_cast<rw_arduino_encoder *>(ctx)->latched;
}

} // namespace

void rw_arduino_encoder_begin(rw_arduino_encoder *enc)
{
    enc->latched.counts = 0u;
    enc->latched.last_edge_us = micros();
    last_edge_us = enc->latched.last_edge_us;
    pinMode(RW_PIN_ENCODER, INPUT_PULLUP);
    attachInterrupt(digitalPinToInterrupt(RW_PIN_ENCODER), on_encoder_edge, RISING);
}

uint32_t rw_arduino_encoder_latch(rw_arduino_encoder *enc)
{
    noInterrupts();
    const uint32_t now_us = micros();
    enc->latched.counts = edge_count;
    enc->latched.last_edge_us = last_edge_us;
    interrupts();
    return now_us;
}

rw_hal_encoder rw_arduino_encoder_hal(rw_arduino_encoder *enc)
{
    rw_hal_encoder hal;
    hal.ctx = enc;
    hal.read = read_encoder;
    return hal;
}
