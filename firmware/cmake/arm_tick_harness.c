/* Bare-metal harness for the ARM build of the firmware core (not the board firmware).
 *
 * Links the core with a fake HAL into an ELF for the SAMD21G18A memory map (samd21g18a.ld), so that
 * arm-none-eabi-size reports what the core really costs in flash and RAM, and an emulator
 * (bench/bench_tick_instructions.py, unicorn) can run rw_core_tick on the Cortex-M0+ instruction set.
 *
 * The fake HAL is driven through plain globals (harness_*) the emulator finds by name and reads/writes:
 *   - encoder: a wheel turning at harness_wheel_rpm, 64 edges per revolution, edges timed exactly;
 *   - battery: harness_battery_mv;
 *   - link: one datagram in harness_rx[0..harness_rx_len) is delivered by the next recv(); reply() and
 *     send() copy the frame into harness_tx[] and count it (harness_tx_kind tells which of the two);
 *   - spindle: an AX-12A in wheel mode that always answers; it turns at the written moving speed (1023 =
 *     59 rpm, about 12 position units per 10 ms read), reads 1023 in its 60 degree dead zone, load
 *     harness_spindle_load_raw, limit switch harness_spindle_switch (so HOME can finish by switch); no reply
 *     at all while harness_spindle_silent is set;
 *   - config store: a fresh device provisioned with the test key harness_test_key (bytes 0..15, never a
 *     real one): harness_init puts rw_config_defaults + rw_config_set_key in harness_flash, load() reads it,
 *     save() keeps what the core writes (its boot counter: the first boot is session 1). Frames on the link
 *     must therefore be signed with that key for harness_session_id().
 * On reset: copy .data, zero .bss, then main() ticks the core every simulated millisecond forever. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rw_core.h"

#define HARNESS_COUNTS_PER_REV 64u
#define HARNESS_TX_REPLY 1u
#define HARNESS_TX_SEND 2u

/* The fake HAL's inputs and outputs: one global each, found by name in the ELF symbol table. */
uint32_t harness_wheel_rpm;                /* in: fake wheel speed, rpm (0 = stopped) */
uint16_t harness_battery_mv;               /* in: fake battery, millivolts */
uint32_t harness_rx_len;                   /* in: bytes waiting in harness_rx (0 = none); cleared by recv */
uint8_t harness_rx[RW_MAX_FRAME_LEN + 1u]; /* in: the next datagram */
uint32_t harness_tx_kind;                  /* out: HARNESS_TX_REPLY or HARNESS_TX_SEND of the last frame out */
uint32_t harness_tx_len;                   /* out: its length */
uint8_t harness_tx[RW_MAX_FRAME_LEN];      /* out: its bytes */
uint32_t harness_tx_count;                 /* out: datagrams out since init */
uint32_t harness_pulse_us;                 /* out: last ESC pulse written, microseconds */
uint32_t harness_spindle_switch;           /* in: home limit switch closed (1) or open (0) */
uint16_t harness_spindle_load_raw;         /* in: present load register */
uint32_t harness_spindle_silent;           /* in: 1 = no reply to the reads (a servo timeout, a lost reply) */
const uint8_t harness_test_key[RW_KEY_LEN] = { 0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u };
rw_config harness_flash;                   /* the fake flash: the stored configuration record */
uint32_t harness_flash_saves;              /* out: save() calls since init */
rw_core harness_core;

/* Fake encoder: edges every 60e6 / (rpm * 64) microseconds of the tick clock (the current rpm). */
static struct {
    uint32_t now_us;
    uint32_t counts;
    uint32_t last_edge_us;
    uint32_t next_edge_us;
} fake_wheel;

static rw_encoder_sample fake_encoder_read(void *ctx)
{
    (void)ctx;
    if (harness_wheel_rpm == 0u) {
        fake_wheel.next_edge_us = fake_wheel.now_us;
    } else {
        /* the edge period once per wheel speed: a board's encoder read is a few capture registers, and a division
         * here on every tick would be counted as the core's */
        static uint32_t period_rpm, period_us;
        if (period_rpm != harness_wheel_rpm) {
            period_rpm = harness_wheel_rpm;
            period_us = 60000000u / (harness_wheel_rpm * HARNESS_COUNTS_PER_REV);
        }
        if ((int32_t)(fake_wheel.next_edge_us - (fake_wheel.last_edge_us + period_us)) > 0) {
            fake_wheel.next_edge_us = fake_wheel.last_edge_us + period_us; /* sped up since the last edge */
        }
        while ((int32_t)(fake_wheel.now_us - fake_wheel.next_edge_us) >= 0) {
            ++fake_wheel.counts;
            fake_wheel.last_edge_us = fake_wheel.next_edge_us;
            fake_wheel.next_edge_us += period_us;
        }
    }
    rw_encoder_sample s = { .counts = fake_wheel.counts, .last_edge_us = fake_wheel.last_edge_us };
    return s;
}

static uint16_t fake_battery_read_mv(void *ctx)
{
    (void)ctx;
    return harness_battery_mv;
}

static void fake_esc_write(void *ctx, uint16_t pulse_us)
{
    (void)ctx;
    harness_pulse_us = pulse_us;
}

/* the board's HAL writes thirds of a microsecond (TCC1): the harness takes that path as the board does */
static void fake_esc_write_third(void *ctx, uint16_t pulse_third_us)
{
    (void)ctx;
    harness_pulse_us = (uint16_t)(((pulse_third_us + 1u) * 21846u) >> 16); /* as the board's HAL: no division */
}

static size_t fake_link_recv(void *ctx, uint8_t *buf, size_t cap)
{
    (void)ctx;
    size_t n = harness_rx_len;
    if (n == 0u) {
        return 0u;
    }
    harness_rx_len = 0u;
    memcpy(buf, harness_rx, n > cap ? cap : n);
    return n > cap ? cap + 1u : n;
}

static void fake_link_out(uint32_t kind, const uint8_t *frame, size_t len)
{
    size_t n = len > sizeof harness_tx ? sizeof harness_tx : len;
    memcpy(harness_tx, frame, n);
    harness_tx_len = (uint32_t)n;
    harness_tx_kind = kind;
    ++harness_tx_count;
}

static void fake_link_reply(void *ctx, const uint8_t *frame, size_t len)
{
    (void)ctx;
    fake_link_out(HARNESS_TX_REPLY, frame, len);
}

static void fake_link_accept_peer(void *ctx)
{
    (void)ctx;
}

static void fake_link_send(void *ctx, const uint8_t *frame, size_t len)
{
    (void)ctx;
    fake_link_out(HARNESS_TX_SEND, frame, len);
}

/* Fake AX-12A: angle in 1/256 position units over the full 360 degrees (1228.8 units), advanced per read. */
#define FAKE_SERVO_TURN_Q8 (1229u * 256u)
static struct {
    uint32_t angle_q8;
    uint16_t moving_speed_raw;
} fake_servo;

static bool fake_spindle_read(void *ctx, rw_spindle_reading *out)
{
    (void)ctx;
    if (harness_spindle_silent != 0u) {
        return false;
    }
    uint32_t step_q8 = 3u * (fake_servo.moving_speed_raw & 0x03FFu); /* 1023 -> 12 units per read */
    if ((fake_servo.moving_speed_raw & 0x0400u) == 0u) {
        fake_servo.angle_q8 = (fake_servo.angle_q8 + step_q8) % FAKE_SERVO_TURN_Q8;
    } else {
        fake_servo.angle_q8 = (fake_servo.angle_q8 + FAKE_SERVO_TURN_Q8 - step_q8) % FAKE_SERVO_TURN_Q8;
    }
    uint32_t position = fake_servo.angle_q8 >> 8;
    out->position_raw = (uint16_t)(position > 1023u ? 1023u : position);
    out->speed_raw = fake_servo.moving_speed_raw;
    out->load_raw = harness_spindle_load_raw;
    out->limit_switch = harness_spindle_switch != 0u;
    return true;
}

static void fake_spindle_write(void *ctx, uint16_t raw)
{
    (void)ctx;
    fake_servo.moving_speed_raw = raw;
}

static uint32_t fake_tick_overruns(void *ctx)
{
    (void)ctx;
    return 0u;
}

static bool fake_config_load(void *ctx, void *buf, size_t len)
{
    (void)ctx;
    if (len != sizeof harness_flash) {
        return false;
    }
    memcpy(buf, &harness_flash, len);
    return true;
}

static bool fake_config_save(void *ctx, const void *buf, size_t len)
{
    (void)ctx;
    if (len != sizeof harness_flash) {
        return false;
    }
    memcpy(&harness_flash, buf, len);
    ++harness_flash_saves;
    return true;
}

static const rw_hal_esc_output harness_esc = { NULL, fake_esc_write, fake_esc_write_third };
static const rw_hal_encoder harness_encoder = { NULL, fake_encoder_read };
static const rw_hal_battery harness_battery = { NULL, fake_battery_read_mv };
static const rw_hal_link harness_link = { NULL, fake_link_recv, fake_link_reply, fake_link_accept_peer, fake_link_send };
static const rw_hal_scheduler harness_scheduler = { NULL, fake_tick_overruns };
static const rw_hal_spindle harness_spindle = { NULL, fake_spindle_read, fake_spindle_write };
/* A PROVISION_COMMIT's write, done at once (a RAM store). */
static uint8_t harness_flash_status;
static bool fake_config_request_save(void *ctx, const void *buf, size_t len)
{
    harness_flash_status = fake_config_save(ctx, buf, len) ? RW_CONFIG_SAVE_DONE : RW_CONFIG_SAVE_FAILED;
    return true;
}

static uint8_t fake_config_save_status(void *ctx)
{
    (void)ctx;
    return harness_flash_status;
}

static const rw_hal_config_store harness_config = { NULL, fake_config_load, fake_config_save, fake_config_request_save,
                                                    fake_config_save_status };
const rw_hal harness_hal = {
    .esc = &harness_esc,
    .encoder = &harness_encoder,
    .battery = &harness_battery,
    .link = &harness_link,
    .scheduler = &harness_scheduler,
    .spindle = &harness_spindle,
    .config = &harness_config,
};

/* Entry points for the emulator (called with the AAPCS: arguments in r0.., return in r0). */
void harness_init(void);
void harness_set_clock(uint32_t now_us);
void harness_tick(uint32_t now_us);
uint8_t harness_state(void);
uint32_t harness_session_id(void);

void harness_init(void)
{
    memset(&fake_wheel, 0, sizeof fake_wheel);
    memset(&fake_servo, 0, sizeof fake_servo);
    fake_servo.angle_q8 = 512u * 256u;
    harness_spindle_switch = 0u;
    harness_spindle_load_raw = 0u;
    harness_spindle_silent = 0u;
    harness_wheel_rpm = 0u;
    harness_battery_mv = 14800u;
    harness_rx_len = 0u;
    harness_tx_count = 0u;
    rw_config_defaults(&harness_flash);
    rw_config_set_key(&harness_flash, harness_test_key);
    harness_flash_saves = 0u;
    harness_flash_status = RW_CONFIG_SAVE_IDLE;
    rw_core_init(&harness_core);
}

/* Advance the fake clock and run one control tick (the emulator may also call rw_core_tick itself
 * with &harness_core, &harness_hal after harness_set_clock). */
void harness_set_clock(uint32_t now_us)
{
    fake_wheel.now_us = now_us;
}

void harness_tick(uint32_t now_us)
{
    harness_set_clock(now_us);
    rw_core_tick(&harness_core, &harness_hal, now_us);
}

uint8_t harness_state(void)
{
    return rw_core_state(&harness_core);
}

/* The session id of this boot (the stored boot counter after the first tick). */
uint32_t harness_session_id(void)
{
    return rw_core_session_id(&harness_core);
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
