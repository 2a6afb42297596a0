/* AX-12A through Dynamixel2Arduino: only the library's raw Protocol 1.0 read/write (DYNAMIXEL::Master) is
 * used, with register addresses and raw values; never its unit conversions (its percent speed unit maps
 * -100..100 % onto raw 0..2047 for AX servos, see core/rw_ax12.h).
 *
 * Bus time at 1 Mbps (10 bits a byte, return delay 0): the read is an 8-byte instruction (80 us) and a
 * 12-byte status packet (120 us), the write a 9-byte instruction (90 us) and a 6-byte status (60 us);
 * with the servo's turnaround and the library's per-byte parsing, about 0.25-0.35 ms for the read and
 * 0.2 ms for the write, both blocking (SerialPortHandler flushes Serial1 and polls for the answer). */
#include "arduino_spindle.h"

#include <Arduino.h>
#include <Dynamixel2Arduino.h>

#include "arduino_board.h"

namespace {

/* The library's packet buffer holds instruction packets only (ours are at most 11 bytes). */
const uint16_t DXL_PACKET_BUFFER_BYTES = 32u;

Dynamixel2Arduino dxl(Serial1, RW_PIN_DXL_DIR, DXL_PACKET_BUFFER_BYTES);

bool write_u8(rw_arduino_spindle *sp, uint16_t addr, uint8_t value, uint32_t timeout_ms)
{
    if (!dxl.write(RW_SPINDLE_DXL_ID, addr, &value, 1u, timeout_ms)) {
        ++sp->write_failures;
        return false;
    }
    return true;
}

bool write_bytes(rw_arduino_spindle *sp, uint16_t addr, const uint8_t *bytes, uint16_t len, uint32_t timeout_ms)
{
    if (!dxl.write(RW_SPINDLE_DXL_ID, addr, bytes, len, timeout_ms)) {
        ++sp->write_failures;
        return false;
    }
    return true;
}

/* Wheel mode: torque off, return delay 0 and both angle limits 0 (EEPROM: written only when they differ),
 * moving speed 0, torque on. */
bool setup_wheel_mode(rw_arduino_spindle *sp)
{
    const uint32_t t = RW_SPINDLE_SETUP_TIMEOUT_MS;
    if (!write_u8(sp, RW_AX12_REG_TORQUE_ENABLE, 0u, t)) {
        return false;
    }
    uint8_t eeprom[5]; /* return delay, CW limit (2), CCW limit (2) */
    if (dxl.read(RW_SPINDLE_DXL_ID, RW_AX12_REG_RETURN_DELAY, sizeof eeprom, eeprom, sizeof eeprom, t) !=
        static_cast<int32_t>(sizeof eeprom)) {
        return false;
    }
    if (eeprom[0] != 0u) {
        if (!write_u8(sp, RW_AX12_REG_RETURN_DELAY, 0u, t)) {
            return false;
        }
        ++sp->eeprom_writes;
    }
    if (eeprom[1] != 0u || eeprom[2] != 0u || eeprom[3] != 0u || eeprom[4] != 0u) {
        const uint8_t limits[4] = { 0u, 0u, 0u, 0u }; /* CW and CCW angle limits, registers 6-9 */
        if (!write_bytes(sp, RW_AX12_REG_CW_ANGLE_LIMIT, limits, sizeof limits, t)) {
            return false;
        }
        ++sp->eeprom_writes;
    }
    const uint8_t stop[2] = { 0u, 0u };
    if (!write_bytes(sp, RW_AX12_REG_MOVING_SPEED, stop, sizeof stop, t) ||
        !write_u8(sp, RW_AX12_REG_TORQUE_ENABLE, 1u, t)) {
        return false;
    }
    ++sp->setups;
    sp->configured = true;
    return true;
}

uint16_t u16_le(const uint8_t *p)
{
    return static_cast<uint16_t>(p[0] | (static_cast<uint16_t>(p[1]) << 8));
}

bool spindle_read(void *ctx, rw_spindle_reading *out)
{
    rw_arduino_spindle *sp = static_cast<rw_arduino_spindle *>(ctx);
    if (sp->silent && millis() - sp->silent_since_ms < RW_SPINDLE_RETRY_MS) {
        return false;
    }
    while (Serial1.available() > 0) { /* a late answer to an earlier, timed-out request: never take it */
        (void)Serial1.read();
    }
    uint8_t regs[6]; /* present position, present speed, present load: registers 36-41 */
    if (dxl.read(RW_SPINDLE_DXL_ID, RW_AX12_REG_PRESENT_POSITION, sizeof regs, regs, sizeof regs,
                 RW_SPINDLE_TIMEOUT_MS) != static_cast<int32_t>(sizeof regs)) {
        ++sp->read_failures;
        sp->silent = true;
        sp->configured = false; /* it may have lost power: torque is off after its reset */
        sp->silent_since_ms = millis();
        return false;
    }
    sp->silent = false;
    ++sp->reads;
    if (!sp->configured && millis() - sp->last_setup_ms >= RW_SPINDLE_RETRY_MS) {
        sp->last_setup_ms = millis();
        (void)setup_wheel_mode(sp); /* a few ms, once, when the servo comes back */
    }
    out->position_raw = u16_le(&regs[0]);
    out->speed_raw = u16_le(&regs[2]);
    out->load_raw = u16_le(&regs[4]);
    out->limit_switch = digitalRead(RW_PIN_SPINDLE_HOME) == LOW;
    return true;
}

void spindle_write_moving_speed_raw(void *ctx, uint16_t raw)
{
    rw_arduino_spindle *sp = static_cast<rw_arduino_spindle *>(ctx);
    if (sp->silent) {
        return; /* nobody answers: writing would only wait for a status packet */
    }
    const uint8_t bytes[2] = { static_cast<uint8_t>(raw & 0xFFu), static_cast<uint8_t>(raw >> 8) };
    (void)write_bytes(sp, RW_AX12_REG_MOVING_SPEED, bytes, sizeof bytes, RW_SPINDLE_TIMEOUT_MS);
}

} // namespace

bool rw_arduino_spindle_begin(rw_arduino_spindle *sp)
{
    *sp = rw_arduino_spindle{};
    pinMode(RW_PIN_SPINDLE_HOME, INPUT_PULLUP);
    dxl.begin(RW_SPINDLE_DXL_BAUD);
    (void)dxl.setPortProtocolVersion(1.0f);
    sp->last_setup_ms = millis();
    if (!setup_wheel_mode(sp)) {
        sp->silent = true;
        sp->silent_since_ms = millis();
        return false;
    }
    return true;
}

rw_hal_spindle rw_arduino_spindle_hal(rw_arduino_spindle *sp)
{
    rw_hal_spindle hal;
    hal.ctx = sp;
    hal.read = spindle_read;
    hal.write_moving_speed_raw = spindle_write_moving_speed_raw;
    return hal;
}
