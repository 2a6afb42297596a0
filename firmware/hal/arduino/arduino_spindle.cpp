/* AX-12A through Dynamixel2Arduino: only the library's raw Protocol 1.0 read/write (DYNAMIXEL::Master) is
 * used, with register addresses and raw values; never its unit conversions (its percent speed unit maps
 * -100..100 % onto raw 0..2047 for AX servos, see core/rw_ax12.h).
 *
 * Bus time at 1 Mbps (10 bits a byte, return delay 0): the read is an 8-byte instruction (80 us) and a
 * 12-byte status packet (120 us), the write a 9-byte instruction (90 us) and a 6-byte status (60 us); with the
 * servo's turnaround and the library's per-byte parsing, about 0.25-0.35 ms for the read and 0.2 ms for the
 * write. The library blocks through each one (it flushes Serial1 and polls for the answer up to its timeout),
 * so they run here, in the background loop, one per pass, never in the tick (arduino_spindle.h). */
#include "arduino_spindle.h"

#include <Arduino.h>
#include <Dynamixel2Arduino.h>

#include "arduino_board.h"

namespace {

/* The library's packet buffer holds instruction packets only (ours are at most 11 bytes). */
const uint16_t DXL_PACKET_BUFFER_BYTES = 32u;

Dynamixel2Arduino dxl(Serial1, RW_PIN_DXL_DIR, DXL_PACKET_BUFFER_BYTES);

void timed(rw_arduino_spindle *sp, uint32_t start_us, bool answered)
{
    const uint32_t took_us = micros() - start_us;
    if (took_us > sp->max_transaction_us) {
        sp->max_transaction_us = took_us;
    }
    ++sp->transactions;
    if (!answered) {
        ++sp->timeouts;
    }
}

bool write_bytes(rw_arduino_spindle *sp, uint16_t addr, const uint8_t *bytes, uint16_t len, uint32_t timeout_ms)
{
    const uint32_t start_us = micros();
    const bool ok = dxl.write(RW_SPINDLE_DXL_ID, addr, bytes, len, timeout_ms);
    timed(sp, start_us, ok);
    return ok;
}

bool read_bytes(rw_arduino_spindle *sp, uint16_t addr, uint8_t *bytes, uint16_t len, uint32_t timeout_ms)
{
    while (Serial1.available() > 0) { /* a late answer to an earlier, timed-out request: never take it */
        (void)Serial1.read();
    }
    const uint32_t start_us = micros();
    const bool ok = dxl.read(RW_SPINDLE_DXL_ID, addr, len, bytes, len, timeout_ms) == static_cast<int32_t>(len);
    timed(sp, start_us, ok);
    return ok;
}

uint16_t u16_le(const uint8_t *p)
{
    return static_cast<uint16_t>(p[0] | (static_cast<uint16_t>(p[1]) << 8));
}

void go_silent(rw_arduino_spindle *sp, uint32_t now_ms)
{
    sp->silent = true;
    sp->silent_since_ms = now_ms;
    sp->failed_in_a_row = RW_SPINDLE_SILENT_AFTER_FAILURES - 1u; /* back from a silence, one miss is silence again */
}

/* One step of the wheel-mode setup: torque off; return delay 0 and both angle limits 0 (EEPROM: written only
 * when they differ); moving speed 0; torque on. A step without an answer abandons the setup (retried when the
 * servo answers a read again, at most every RW_SPINDLE_RETRY_MS). */
void setup_step(rw_arduino_spindle *sp, uint32_t now_ms)
{
    const uint32_t t = RW_SPINDLE_SETUP_TIMEOUT_MS;
    bool ok = true;
    uint8_t next = RW_SPINDLE_SETUP_DONE;
    switch (sp->setup_step) {
    case RW_SPINDLE_SETUP_TORQUE_OFF: {
        const uint8_t off = 0u;
        ok = write_bytes(sp, RW_AX12_REG_TORQUE_ENABLE, &off, 1u, t);
        next = RW_SPINDLE_SETUP_READ_EEPROM;
        break;
    }
    case RW_SPINDLE_SETUP_READ_EEPROM:
        ok = read_bytes(sp, RW_AX12_REG_RETURN_DELAY, sp->eeprom, sizeof sp->eeprom, t);
        next = RW_SPINDLE_SETUP_RETURN_DELAY;
        break;
    case RW_SPINDLE_SETUP_RETURN_DELAY:
        if (sp->eeprom[0] != 0u) {
            const uint8_t zero = 0u;
            ok = write_bytes(sp, RW_AX12_REG_RETURN_DELAY, &zero, 1u, t);
            sp->eeprom_writes += ok ? 1u : 0u;
        }
        next = RW_SPINDLE_SETUP_ANGLE_LIMITS;
        break;
    case RW_SPINDLE_SETUP_ANGLE_LIMITS:
        if (sp->eeprom[1] != 0u || sp->eeprom[2] != 0u || sp->eeprom[3] != 0u || sp->eeprom[4] != 0u) {
            const uint8_t limits[4] = { 0u, 0u, 0u, 0u }; /* CW and CCW angle limits, registers 6-9 */
            ok = write_bytes(sp, RW_AX12_REG_CW_ANGLE_LIMIT, limits, sizeof limits, t);
            sp->eeprom_writes += ok ? 1u : 0u;
        }
        next = RW_SPINDLE_SETUP_STOP;
        break;
    case RW_SPINDLE_SETUP_STOP: {
        const uint8_t stop[2] = { 0u, 0u };
        ok = write_bytes(sp, RW_AX12_REG_MOVING_SPEED, stop, sizeof stop, t);
        next = RW_SPINDLE_SETUP_TORQUE_ON;
        break;
    }
    case RW_SPINDLE_SETUP_TORQUE_ON: {
        const uint8_t on = 1u;
        ok = write_bytes(sp, RW_AX12_REG_TORQUE_ENABLE, &on, 1u, t);
        if (ok) {
            ++sp->setups;
        }
        next = RW_SPINDLE_SETUP_DONE;
        break;
    }
    default:
        break;
    }
    if (!ok) {
        sp->setup_step = RW_SPINDLE_SETUP_DONE;
        go_silent(sp, now_ms);
        return;
    }
    sp->setup_step = next;
}

} // namespace

void rw_arduino_spindle_begin(rw_arduino_spindle *sp)
{
    *sp = rw_arduino_spindle{};
    rw_spindle_exchange_init(&sp->exchange);
    pinMode(RW_PIN_SPINDLE_HOME, INPUT_PULLUP);
    dxl.begin(RW_SPINDLE_DXL_BAUD);
    (void)dxl.setPortProtocolVersion(1.0f);
    sp->setup_step = RW_SPINDLE_SETUP_TORQUE_OFF;
    sp->last_setup_ms = millis();
}

void rw_arduino_spindle_service(rw_arduino_spindle *sp, uint32_t now_ms)
{
    rw_spindle_exchange *ex = &sp->exchange;
    const rw_spindle_job job = rw_spindle_exchange_next_job(ex);
    if (sp->silent && now_ms - sp->silent_since_ms >= RW_SPINDLE_RETRY_MS) {
        sp->silent = false; /* try the bus again */
    }
    if (sp->silent) {
        /* nobody answers: a read reports "no answer" at once, a write would only wait for a status packet */
        if (job.kind == RW_SPINDLE_JOB_READ) {
            rw_spindle_exchange_read_done(ex, &job, nullptr);
            ++sp->skipped_silent;
        } else if (job.kind == RW_SPINDLE_JOB_WRITE) {
            rw_spindle_exchange_write_done(ex, &job, false);
            ++sp->skipped_silent;
        }
        return;
    }
    if (sp->setup_step != RW_SPINDLE_SETUP_DONE) {
        setup_step(sp, now_ms);
        return;
    }
    if (job.kind == RW_SPINDLE_JOB_WRITE) {
        const uint8_t bytes[2] = { static_cast<uint8_t>(job.moving_speed_raw & 0xFFu),
                                   static_cast<uint8_t>(job.moving_speed_raw >> 8) };
        rw_spindle_exchange_write_done(ex, &job, write_bytes(sp, RW_AX12_REG_MOVING_SPEED, bytes, sizeof bytes,
                                                             RW_SPINDLE_TIMEOUT_MS));
        return;
    }
    if (job.kind != RW_SPINDLE_JOB_READ) {
        return;
    }
    uint8_t regs[6]; /* present position, present speed, present load: registers 36-41 */
    if (!read_bytes(sp, RW_AX12_REG_PRESENT_POSITION, regs, sizeof regs, RW_SPINDLE_TIMEOUT_MS)) {
        rw_spindle_exchange_read_done(ex, &job, nullptr);
        if (++sp->failed_in_a_row < RW_SPINDLE_SILENT_AFTER_FAILURES) {
            return; /* a lost reply: the next read tries again */
        }
        go_silent(sp, now_ms);
        /* it may have lost power: torque is off after its reset, so set wheel mode up when it answers again */
        if (now_ms - sp->last_setup_ms >= RW_SPINDLE_RETRY_MS) {
            sp->last_setup_ms = now_ms;
            sp->setup_step = RW_SPINDLE_SETUP_TORQUE_OFF;
        }
        return;
    }
    sp->failed_in_a_row = 0u;
    rw_spindle_reading reading;
    reading.position_raw = u16_le(&regs[0]);
    reading.speed_raw = u16_le(&regs[2]);
    reading.load_raw = u16_le(&regs[4]);
    reading.limit_switch = digitalRead(RW_PIN_SPINDLE_HOME) == LOW;
    rw_spindle_exchange_read_done(ex, &job, &reading);
}

rw_hal_spindle rw_arduino_spindle_hal(rw_arduino_spindle *sp)
{
    return rw_spindle_exchange_hal(&sp->exchange);
}
