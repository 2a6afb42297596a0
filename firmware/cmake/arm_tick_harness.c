/* Bare-metal harness for the ARM build of the firmware core (not the board firmware).
 *
 * Links the core with a fake HAL into an ELF for the SAMD21G18A memory map (samd21g18a.ld), so that
 * arm-none-eabi-size reports what the core really costs in flash and RAM, and an emulator
 * (bench/bench_tick_instructions.py, unicorn) can run rw_core_tick on the Cortex-M0+ instruction set.
 *
 * The fake HAL is driven through harness_io, a plain global the emulator reads and writes:
 *   - encoder: a wheel turning at wheel_rpm, 64 edges per revolution, edges timed exactly;
 *   - battery: battery_mv;
 *   - link: one datagram in rx[0..rx_len) is delivered by the next recv(); reply() and send() copy the
 *     frame into tx[] and count it (tx_kind tells which of the two).
 * On reset: copy .data, zero .bss, then main() ticks the core every simulated millisecond forever. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rw_core.h"

#define HARNESS_COUNTS_PER_REV 64u
#define HARNESS_TX_REPLY 1u
#define HARNESS_TX_SEND 2u

typedef struct harness_io {
    uint32_t wheel_rpm;        /* fake wheel speed, rpm (0 = stopped) */
    uint16_t battery_mv;       /* fake battery, millivolts */
    uint16_t rx_len;           /* bytes waiting in rx (0 = none) */
    uint8_t rx[RW_MAX_FRAME_LEN + 1u];
    uint8_t tx_kind;           /* HARNESS_TX_REPLY or HARNESS_TX_SEND of the last frame out */
    uint8_t tx_len;
    uint8_t tx[RW_MAX_FRAME_LEN];
    uint32_t tx_count;         /* datagrams out since boot */
    uint16_t pulse_us;         /* last ESC pulse written */
    uint32_t now_us;           /* tick clock the fake encoder is timed against */
    /* fake encoder state */
    uint32_t enc_counts;
    uint32_t enc_last_edge_us;
    uint32_t enc_next_edge_us;
} harness_io;

harness_io harness_io_block;
rw_core harness_core;

static rw_encoder_sample fake_encoder_read(void *ctx)
{
    harness_io *io = ctx;
    if (io->wheel_rpm == 0u) {
        io->enc_next_edge_us = io->now_us;
    } else {
        uint32_t period_us = 60000000u / (io->wheel_rpm * HARNESS_COUNTS_PER_REV);
        while ((int32_t)(io->now_us - io->enc_next_edge_us) >= 0) {
            ++io->enc_counts;
            io->enc_last_edge_us = io->enc_next_edge_us;
            io->enc_next_edge_us += period_us;
        }
    }
    rw_encoder_sample s = { .counts = io->enc_counts, .last_edge_us = io->enc_last_edge_us };
    return s;
}

static uint16_t fake_battery_read_mv(void *ctx)
{
    return ((const harness_io *)ctx)->battery_mv;
}

static void fake_esc_write(void *ctx, uint16_t pulse_us)
{
    ((harness_io *)ctx)->pulse_us = pulse_us;
}

static size_t fake_link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    harness_io *io = ctx;
    size_t n = io->rx_len;
    if (n == 0u) {
        return 0u;
    }
    io->rx_len = 0u;
    memcpy(buf, io->rx, n > cap ? cap : n);
    return n > cap ? cap + 1u : n;
}

static void fake_link_out(harness_io *io, uint8_t kind, const uint8_t *frame, size_t len)
{
    size_t n = len > sizeof io->tx ? sizeof io->tx : len;
    memcpy(io->tx, frame, n);
    io->tx_len = (uint8_t)n;
    io->tx_kind = kind;
    ++io->tx_count;
}

static void fake_link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    fake_link_out(ctx, HARNESS_TX_REPLY, frame, len);
}

static void fake_link_accept_peer(void *ctx)
{
    (void)ctx;
}

static void fake_link_send(void *ctx, const uint8_t *frame, size_t len)
{
    fake_link_out(ctx, HARNESS_TX_SEND, frame, len);
}

static uint32_t fake_tick_overruns(void *ctx)
{
    (void)ctx;
    return 0u;
}

static const rw_hal_esc_output harness_esc = { &harness_io_block, fake_esc_write };
static const rw_hal_encoder harness_encoder = { &harness_io_block, fake_encoder_read };
static const rw_hal_battery harness_battery = { &harness_io_block, fake_battery_read_mv };
static const rw_hal_link harness_link = {
    &harness_io_block, fake_link_recv, fake_link_reply, fake_link_accept_peer, fake_link_send,
};
static const rw_hal_scheduler harness_scheduler = { &harness_io_block, fake_tick_overruns };
const rw_hal harness_hal = {
    .esc = &harness_esc,
    .encoder = &harness_encoder,
    .battery = &harness_battery,
    .link = &harness_link,
    .scheduler = &harness_scheduler,
};

/* Entry points for the emulator (called with the AAPCS: arguments in r0.., return in r0). */
void harness_init(void);
void harness_tick(uint32_t now_us);
uint8_t harness_state(void);

void harness_init(void)
{
    memset(&harness_io_block, 0, sizeof harness_io_block);
    harness_io_block.battery_mv = 14800u;
    rw_core_init(&harness_core);
}

void harness_tick(uint32_t now_us)
{
    harness_io_block.now_us = now_us;
    rw_core_tick(&harness_core, &harness_hal, now_us);
}

uint8_t harness_state(void)
{
    return rw_core_state(&harness_core);
}

int main(void);

int main(void)
{
    harness_init();
    uint32_t now_us = 0u;
    for (;;) {
        now_us += 1000u;
        harness_tick(now_us);
    }
}

/* ---- Startup: vector table and reset handler (what the Arduino core's startup does, minus clocks) ---- */

extern uint32_t __data_start, __data_end, __data_load, __bss_start, __bss_end, __stack_top;

void Reset_Handler(void);
void Fault_Handler(void);

void Reset_Handler(void)
{
    const uint32_t *src = &__data_load;
    for (uint32_t *dst = &__data_start; dst < &__data_end;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = &__bss_start; dst < &__bss_end;) {
        *dst++ = 0u;
    }
    (void)main();
    for (;;) {
    }
}

void Fault_Handler(void)
{
    for (;;) {
    }
}

/* Initial stack pointer, reset, NMI, HardFault; the rest of the Cortex-M0+ table is unused here. */
__attribute__((section(".vectors"), used)) static void (*const harness_vectors[4])(void) = {
    (void (*)(void))&__stack_top, Reset_Handler, Fault_Handler, Fault_Handler,
};
