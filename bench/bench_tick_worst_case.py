"""Worst-case timing model of the board's control tick (issue 17): the worst tick and the worst jitter of the
ESC update while the rope is airborne, on every path, with the board's tick in the TC3 interrupt and every bus
wait in the background loop.

How the figure is built:

1. The tick's own cycles, emulated (unicorn, the cycle model of tests/firmware_arm/arm_harness_emulator.py, as
   bench/bench_tick_instructions.py): the core driven to AIRBORNE at 5 m/s with the spindle moving and a signed
   link, then the worst rw_core_tick of each path:
     periodic     the schedule with nothing received (speed loop, spindle step, telemetry pack, signing steps)
     command      a SET_ROPE_SPEED / PARAM_SET arriving at every phase of the schedule (tag check, execution,
                  the ACK signed in one piece)
     telemetry    the tick whose frame leaves (the last signing blocks + the send into the HAL's queue)
     servo timeout  the spindle steps without a reading (the fake servo silent: dead reckoning)
     WiFi reconnect the periodic ticks: a reconnect runs in the background loop, the tick does not see it
   For each, also the cycles until the core writes the ESC pulse: where the pulse would go out if the HAL wrote
   it at once (it does not: see 3).
2. One flash wait state at 48 MHz: every software cycle x FLASH_FACTOR (1.5, the upper bound with the cache).
3. The board's side, from its code (firmware/hal/arduino, ArduinoCore-samd 1.8.14): the TC3 handler's fixed
   work around the tick (counter read, micros() twice, the staged pulse applied first in the tick, the encoder
   latch, the watchdog feed), and what can delay or stretch the tick: interrupts of higher priority (encoder
   edges at 15,000 rpm, the spindle UART's bytes during a transaction), SysTick at equal priority, and the
   longest sections that mask interrupts or the tick (the USB receive copy of one byte, the copy of
   the tick statistics). USB is below the tick and never delays it.
   The ESC update is the staged pulse written to TCC1 first thing in the tick: its jitter is the spread of the
   tick's entry delay (interrupt latency) plus the spread of the few cycles before the write, whatever the
   previous tick did.
4. The background loop, bounded from the libraries' transaction counts at their bus speeds: the AX-12A at
   1 Mbps (Dynamixel2Arduino: instruction and status packets, its millisecond timeouts), WiFiNINA over SPI at
   8 MHz (calls per datagram; each call's waits bounded by our ready-line check), USB. These costs never enter
   the tick; they set how old a reading or a command is when the tick gets it.

Target (issue 17): no tick over its period, and the ESC update's jitter under 50 us, on every path.

    uv run python bench/bench_tick_worst_case.py
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT / "tests" / "firmware_arm"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import arm_harness_emulator as ah  # noqa: E402
import bench_tick_instructions as bti  # noqa: E402
from robowrangler.protocol import generated as proto  # noqa: E402

CPU_HZ = 48_000_000
TICK_US = 1000
FLASH_FACTOR = 1.5  # one flash wait state at 48 MHz, partly hidden by the cache: the upper bound
JITTER_TARGET_US = 50.0
TOP_RPM = 15_000
COUNTS_PER_REV = 64

# ---- the board's code around the tick, Cortex-M0+ cycles at zero wait states (counted from the sources) ----
IRQ_ENTRY_CYCLES = 15  # Cortex-M0+ exception entry (stacking), fixed
IRQ_EXIT_CYCLES = 13
# TC3_Handler before the tick function: READREQ + sync of COUNT (~4 cycles of the 48 MHz GCLK + APB), INTFLAG
# clear, micros() (SysTick->VAL, ICSR, _ulTickCount, one pass; a second pass when SysTick wrapped meanwhile),
# the overrun checks; then control_tick's first call, rw_arduino_esc_output_apply (a compare; when the pulse
# changed: LUPD set, CCB0/CCB1 written, LUPD cleared, each with a SYNCBUSY poll of TCC1).
TC3_PRE_TICK_CYCLES = 110
TC3_PRE_TICK_SPREAD_CYCLES = 30  # micros()'s second pass
ESC_APPLY_CYCLES = 70
# The rest of the handler: encoder latch (cpsid, micros(), two loads, cpsie), the background-stall check and the
# watchdog feed (WDT SYNCBUSY read, CLEAR write), micros() and the statistics at the end.
TC3_POST_CYCLES = 220
# Interrupts above the tick.
ENCODER_ISR_CYCLES = 150  # EIC_Handler's loop over one enabled line, the callback: micros() and two stores
UART_ISR_CYCLES = 100  # SERCOM5_Handler -> Uart::IrqHandler: one byte to or from the ring buffer
SYSTICK_ISR_CYCLES = 45  # equal priority to the tick: a running one finishes first
# Longest sections that keep the tick out.
USB_RX_CHUNK_MASKED_CYCLES = 1 * 12 + 30  # DoubleBufferedEPOutHandler::recv of the one byte Serial.read() takes, PRIMASK set
STATS_COPY_MASKED_CYCLES = 40  # rw_arduino_scheduler_stats: TC3 disabled in the NVIC for four loads
CONFIG_COPY_MASKED_CYCLES = 350  # main.cpp's copy of a committed record (272 bytes): DISARMED only, not in flight

# ---- buses (background loop) ----
DXL_BIT_US = 1.0  # 1 Mbps
DXL_BYTE_US = 10 * DXL_BIT_US  # start + 8 data + stop
DXL_READ_BYTES = (8, 12)  # READ of 6 bytes from register 36: instruction, status
DXL_WRITE_BYTES = (9, 6)  # WRITE of 2 bytes to register 32
UART_BYTES_PER_SPINDLE_PERIOD = sum(DXL_READ_BYTES) + sum(DXL_WRITE_BYTES) - 2  # interrupts per 10 ms
DXL_TURNAROUND_US = 40  # return delay 0 (register 5) + the servo's processing: assumed, measure on the bench
DXL_TIMEOUT_MS = 2  # RW_SPINDLE_TIMEOUT_MS: Dynamixel2Arduino counts whole millis(): at most 2 ms + 1 tick
DXL_SETUP_TIMEOUT_MS = 10  # RW_SPINDLE_SETUP_TIMEOUT_MS, one setup step per pass
SPI_HZ = 8_000_000  # SpiDrv::spiSlaveSelect: SPISettings(8000000, MSBFIRST, SPI_MODE0)
SPI_BYTE_US = 8 / SPI_HZ * 1e6 + 1.0  # SPIClass::transfer polls each byte: ~1 us of software a byte
NINA_TURNAROUND_US = 100  # the module's time to prepare an answer: assumed, measure on the bench
NINA_READY_WAIT_BOUND_US = 2000  # RW_LINK_CALL_READY_WAIT_US: our bound before every call
NINA_SELECT_BOUND_US = 5000  # SpiDrv::spiSlaveSelect waits at most 5 ms for the line to rise
# WiFiNINA 1.9.1 calls per datagram and their SPI bytes (command + reply, 4-byte padding, parameters)
NINA_RX_CALLS = (("availData", 8, 8), ("getRemoteData (remoteIP)", 8, 14), ("getRemoteData (remotePort)", 8, 14),
                 ("getDataBuf", 12, 12))  # + the datagram's bytes in getDataBuf
NINA_TX_CALLS = (("startClient", 20, 8), ("insertDataBuf", 12, 8), ("sendUdpData", 8, 8))  # + datagram in insertDataBuf
NINA_POLL_CALLS = (("getConnectionStatus", 8, 8),)
DATAGRAM_BYTES = 93  # RW_MAX_FRAME_LEN: the longest frame
USB_PASS_CYCLES = 64 * 90 + 2000 + 63 * 4  # 64 bytes through Serial.read + the deframer, one encode, one packet


# PARAM_SET of a parameter of each group (rw_params_modules): the group and the parameter sent (its default).
PARAM_SET_GROUPS = {
    "speed loop gains": "speed_kp",
    "setpoint ramp": "ramp_up_mps2",
    "speed filter": "speed_filter_tau_s",
    "ToV guard": "tov_mps",
    "spindle": "spindle_kp_per_s",
    "load monitor": "load_loss_drop_n",
    "throttle map + load monitor": "motor_kv_rpm_per_v",
    "telemetry": "telemetry_rate_hz",
}
PARAM_SET_FOLLOW_TICKS = 4  # a staged module is converted at the end of the first tick without a datagram


def us(cycles: float) -> float:
    return cycles / CPU_HZ * 1e6


@dataclass
class PathCost:
    name: str
    tick_cycles: int  # emulated rw_core_tick, zero wait states
    esc_write_cycles: int  # emulated cycles until the core wrote the pulse (its HAL call)


class EscWriteProbe:
    """Records, during a counted tick, the emulated cycle count when the core calls the ESC HAL."""

    def __init__(self, emu: ah.HarnessEmulator) -> None:
        from unicorn import UC_HOOK_CODE

        self.emu = emu
        self.at_cycles: int | None = None
        sym = emu.symbols["fake_esc_write"]
        self._hook = emu.uc.hook_add(UC_HOOK_CODE, self._on_call, begin=sym.address, end=sym.address + 1)

    def _on_call(self, uc, address, size, user) -> None:  # noqa: ANN001
        if self.at_cycles is None and self.emu._profile is not None:  # noqa: SLF001
            self.at_cycles = self.emu._profile.cycles  # noqa: SLF001

    def reset(self) -> None:
        self.at_cycles = None


def emulate_paths() -> list[PathCost]:
    elf = ah.build_arm()
    emu = ah.HarnessEmulator(elf)
    probe = EscWriteProbe(emu)
    sc = bti.Scenario(emu)
    sc.to_airborne()

    def counted(datagram: bytes | None = None):  # noqa: ANN202
        probe.reset()
        sent, profile = sc.tick(datagram, count=True)
        return sent, profile, probe.at_cycles or 0

    worst: dict[str, PathCost] = {}

    def keep(name: str, profile: ah.CallProfile, esc_at: int) -> None:
        if name not in worst or profile.cycles > worst[name].tick_cycles:
            worst[name] = PathCost(name, profile.cycles, max(esc_at, worst.get(name, PathCost(name, 0, 0)).esc_write_cycles))
        else:
            worst[name].esc_write_cycles = max(worst[name].esc_write_cycles, esc_at)

    for _ in range(bti.SCHEDULE_TICKS):
        _, profile, esc_at = counted()
        label = bti.tick_label(profile)
        keep("periodic (no datagram)", profile, esc_at)
        if "mac finish+send" in label:
            keep("telemetry frame leaving", profile, esc_at)
    commands = (
        ("SET_ROPE_SPEED", lambda: proto.SetRopeSpeed(rope_speed_mmps=bti.TARGET_MMPS)),
        ("SET_LOOP", lambda: proto.SetLoop(guide_position_um=bti.LOOP_TARGET_UM)),
        ("PARAM_GET", lambda: proto.ParamGet(param_id=proto.PARAMS_BY_NAME["speed_kp"].id)),
    )
    for name, make in commands:
        for _ in range(bti.PHASES):
            sent, profile, esc_at = counted(sc.frame(make()))
            assert sent and isinstance(sent[0], proto.Ack), sent
            keep(f"command arriving ({name})", profile, esc_at)
    # PARAM_SET of each parameter group: the tick that takes it (checked, stored, ACK signed, PARAM_CHANGED and
    # PARAM_VALUE queued) and the ticks after it, one of which converts its staged modules at its end
    for name in PARAM_SET_GROUPS.values():
        spec = proto.PARAMS_BY_NAME[name]
        for _ in range(bti.PHASES):
            sent, profile, esc_at = counted(sc.frame(proto.ParamSet(param_id=spec.id, value=spec.default)))
            assert sent and isinstance(sent[0], proto.Ack), sent
            keep(f"command arriving (PARAM_SET {name})", profile, esc_at)
            for _ in range(PARAM_SET_FOLLOW_TICKS):
                _, profile, esc_at = counted()
                keep(f"ticks after PARAM_SET {name}", profile, esc_at)
    sc.run_quiet(40)
    emu.write_u32("harness_spindle_silent", 1)  # the servo stops answering: every spindle step times out
    for _ in range(bti.SCHEDULE_TICKS):
        _, profile, esc_at = counted()
        if profile.per_function.get("rw_spindle_step"):
            keep("servo timeout (step without reading)", profile, esc_at)
    emu.write_u32("harness_spindle_silent", 0)
    for _ in range(bti.SCHEDULE_TICKS):  # a reconnect is background work: the tick runs its plain schedule
        _, profile, esc_at = counted()
        keep("WiFi reconnect (background)", profile, esc_at)
    assert emu.state() == proto.State.AIRBORNE, "the rope must stay airborne through every path"
    return list(worst.values())


def commit_crc_cycles() -> int:
    """Emulated cycles of the CRC-32 a PROVISION_COMMIT's tick computes over the configuration record (the one
    float-free but long piece of work left in that tick; the flash write itself runs in the background loop)."""
    emu = ah.HarnessEmulator(ah.build_arm())
    emu.reset()
    record = emu.symbols["harness_flash"]
    _, profile = emu.call("rw_crc32", record.address, record.size - 4, count=True)  # all but the CRC field
    return profile.cycles


def interrupt_load(window_us: float, *, uart_active: bool) -> float:
    """Cycles (zero wait states) the interrupts above the tick can take within a window: encoder edges at
    TOP_RPM and, during a spindle transaction, one UART byte every 10 us."""
    edge_period_us = 60e6 / (TOP_RPM * COUNTS_PER_REV)
    edges = math.floor(window_us / edge_period_us) + 1
    cycles = edges * (ENCODER_ISR_CYCLES + IRQ_ENTRY_CYCLES + IRQ_EXIT_CYCLES)
    if uart_active:
        # a byte every 10 us while a transaction is on the bus, at most the read's and the write's bytes (the
        # first byte of each instruction goes straight to DATA, the rest through the DRE interrupt) per 10 ms
        bytes_ = min(math.floor(window_us / DXL_BYTE_US) + 1, UART_BYTES_PER_SPINDLE_PERIOD)
        cycles += bytes_ * (UART_ISR_CYCLES + IRQ_ENTRY_CYCLES + IRQ_EXIT_CYCLES)
    return cycles


def entry_delay_us(masked_cycles: int) -> float:
    """Worst delay from the period boundary to the first instruction of the tick's handler: the longest section
    that keeps it out, or a SysTick handler at equal priority, then the interrupts above it that arrive
    meanwhile (a fixed point), then the exception entry."""
    blocking = max(masked_cycles, SYSTICK_ISR_CYCLES + IRQ_ENTRY_CYCLES + IRQ_EXIT_CYCLES) * FLASH_FACTOR
    delay = blocking
    for _ in range(20):
        new = blocking + interrupt_load(us(delay), uart_active=True) * FLASH_FACTOR
        if abs(new - delay) < 1:
            break
        delay = new
    return us(delay + IRQ_ENTRY_CYCLES)


def tick_duration_us(tick_cycles: int) -> float:
    """Worst time from the period boundary to the end of the tick, with the interrupts above it (fixed point)."""
    own = (tick_cycles + TC3_PRE_TICK_CYCLES + TC3_PRE_TICK_SPREAD_CYCLES + ESC_APPLY_CYCLES + TC3_POST_CYCLES
           + IRQ_EXIT_CYCLES) * FLASH_FACTOR
    start = entry_delay_us(USB_RX_CHUNK_MASKED_CYCLES)
    t = us(own)
    for _ in range(30):
        new = us(own + interrupt_load(t, uart_active=True) * FLASH_FACTOR)
        if abs(new - t) < 0.01:
            break
        t = new
    return start + t


def dxl_transaction_us(bytes_: tuple[int, int]) -> float:
    return (bytes_[0] + bytes_[1]) * DXL_BYTE_US + DXL_TURNAROUND_US


def nina_calls_us(calls: tuple[tuple[str, int, int], ...], payload_bytes: int, *, bounded: bool) -> float:
    """Nominal: the SPI bytes plus the module's turnaround per call; bounded: with our ready-line bound and the
    library's 5 ms select loop in place of the turnaround."""
    total = 0.0
    for _name, cmd_bytes, reply_bytes in calls:
        total += (cmd_bytes + reply_bytes) * SPI_BYTE_US
        total += (NINA_READY_WAIT_BOUND_US + NINA_SELECT_BOUND_US) if bounded else NINA_TURNAROUND_US
    return total + payload_bytes * SPI_BYTE_US


def main() -> None:
    paths = emulate_paths()
    print("Worst-case timing model of the control tick (TC3 interrupt, 1 ms), airborne at 5 m/s, encoder at "
          f"{TOP_RPM:,} rpm ({TOP_RPM * COUNTS_PER_REV / 60 / 1000:.1f} kHz of edges), spindle transactions on the bus,")
    print(f"every software cycle x {FLASH_FACTOR} (one flash wait state). Tick cycles emulated (unicorn); the board's "
          "handler and interrupt costs counted from its sources (constants at the top of this file).")
    print()
    # ESC update: applied at the handler's start, a fixed number of cycles after entry
    latency_worst = entry_delay_us(USB_RX_CHUNK_MASKED_CYCLES)
    latency_best = us(IRQ_ENTRY_CYCLES)
    esc_best = latency_best + us(TC3_PRE_TICK_CYCLES * FLASH_FACTOR)
    esc_worst = latency_worst + us((TC3_PRE_TICK_CYCLES + TC3_PRE_TICK_SPREAD_CYCLES) * FLASH_FACTOR)
    jitter = esc_worst - esc_best
    header = (f"{'path':<40}{'tick cyc':>9}{'worst tick us':>14}{'of period':>10}{'ESC at us':>10}"
              f"{'ESC jitter us':>14}{'  if written in the tick: at us':>32}")
    print(header)
    print("-" * len(header))
    missed = []
    in_tick_min = min(p.esc_write_cycles for p in paths)
    for p in paths:
        t_us = tick_duration_us(p.tick_cycles)
        in_tick_us = us(p.esc_write_cycles * FLASH_FACTOR) + esc_best
        # a tick past its period delays the next one's entry, and with it the next ESC update, by the excess
        path_jitter = jitter + max(0.0, t_us - TICK_US)
        if t_us >= TICK_US or path_jitter >= JITTER_TARGET_US:
            missed.append(p.name)
        print(f"{p.name:<40}{p.tick_cycles:>9}{t_us:>14.0f}{t_us / TICK_US:>10.0%}{esc_best:>6.1f}-{esc_worst:<4.1f}"
              f"{path_jitter:>13.1f}{in_tick_us:>28.0f}")
    ok = not missed
    spread_in_tick = us((max(p.esc_write_cycles for p in paths) - in_tick_min) * FLASH_FACTOR) + jitter
    print()
    print(f"ESC update: the pulse staged by the previous tick is written first in the handler, {esc_best:.1f}-"
          f"{esc_worst:.1f} us after the period boundary on every path: jitter {jitter:.1f} us (target "
          f"< {JITTER_TARGET_US:.0f} us), more only after a tick that ran past its period. Written where the core computes it, the spread over these paths would be "
          f"{spread_in_tick:.0f} us (the command path's tag check and ACK come first).")
    print(f"Entry delay, worst: {latency_worst:.1f} us = the longest section keeping the tick out "
          f"(USB receive of one byte {USB_RX_CHUNK_MASKED_CYCLES} cycles; SysTick {SYSTICK_ISR_CYCLES}) + encoder and UART "
          "interrupts arriving meanwhile.")
    crc_cycles = commit_crc_cycles()
    print(f"Not in flight: a PROVISION_COMMIT (DISARMED only) seals its record in the tick (CRC-32 of the record: "
          f"{crc_cycles:,} cycles, {us(crc_cycles * FLASH_FACTOR):.0f} us with the wait state, on top of a command "
          "tick) and hands a copy to the store; the flash erase + write runs in the background loop and the "
          "command is ACKed when it is done (up to ~25 ms with the CPU stalled on flash: ticks in that window "
          "start late, counted in tick_overruns, the PWM runs on in hardware; ARM is refused until then). The "
          f"background loop copies the committed record with the tick masked "
          f"({us(CONFIG_COPY_MASKED_CYCLES * FLASH_FACTOR):.1f} us).")
    print()
    # UART receiver deadline: a byte every 10 us, the SERCOM holds 2 (one in the shift register)
    uart_deadline_us = 2 * DXL_BYTE_US
    uart_latency_us = us((ENCODER_ISR_CYCLES + IRQ_ENTRY_CYCLES + IRQ_EXIT_CYCLES + USB_RX_CHUNK_MASKED_CYCLES
                          + IRQ_ENTRY_CYCLES) * FLASH_FACTOR)
    print(f"Spindle UART (priority 1, above the tick): worst service latency {uart_latency_us:.1f} us (one encoder "
          f"handler + the longest masked section) against its receiver's {uart_deadline_us:.0f} us: "
          f"{'no byte lost' if uart_latency_us < uart_deadline_us else 'BYTES CAN BE LOST'}. Below the tick (the core's "
          f"default, 3) it would wait for a whole tick ({tick_duration_us(max(p.tick_cycles for p in paths)):.0f} us "
          "worst): every reply overlapping a long tick lost.")
    print()
    # background loop
    read_us = dxl_transaction_us(DXL_READ_BYTES)
    write_us = dxl_transaction_us(DXL_WRITE_BYTES)
    dxl_timeout_us = (DXL_TIMEOUT_MS + 1) * 1000
    setup_us = (DXL_SETUP_TIMEOUT_MS + 1) * 1000
    rx_nom = nina_calls_us(NINA_RX_CALLS, DATAGRAM_BYTES, bounded=False)
    tx_nom = nina_calls_us(NINA_TX_CALLS, DATAGRAM_BYTES, bounded=False)
    rx_bound = nina_calls_us(NINA_RX_CALLS, DATAGRAM_BYTES, bounded=True)
    tx_bound = nina_calls_us(NINA_TX_CALLS, DATAGRAM_BYTES, bounded=True)
    usb_us = us(USB_PASS_CYCLES * FLASH_FACTOR)
    tick_share = max(tick_duration_us(p.tick_cycles) for p in paths if p.name.startswith("periodic")) / TICK_US
    print("Background loop (never inside the tick), one pass = one spindle transaction + one WiFi step + USB:")
    print(f"  AX-12A read {read_us:.0f} us, write {write_us:.0f} us (1 Mbps, {DXL_TURNAROUND_US} us turnaround "
          f"assumed); no reply: <= {dxl_timeout_us / 1000:.0f} ms (timeout {DXL_TIMEOUT_MS} ms in whole millis); a "
          f"wheel-mode setup step <= {setup_us / 1000:.0f} ms (six steps, one per pass, after a silence only)")
    print(f"  WiFiNINA (SPI 8 MHz): a datagram in = {len(NINA_RX_CALLS)} calls {rx_nom:.0f} us nominal, <= "
          f"{rx_bound / 1000:.1f} ms bounded; out = {len(NINA_TX_CALLS)} calls {tx_nom:.0f} us nominal, <= "
          f"{tx_bound / 1000:.1f} ms bounded ({NINA_TURNAROUND_US} us module turnaround assumed; bounded: our "
          f"{NINA_READY_WAIT_BOUND_US / 1000:.0f} ms ready-line wait + the library's 5 ms select loop per call)")
    print(f"  USB serial: {usb_us:.0f} us")
    nominal_pass = (max(read_us, write_us) + rx_nom + tx_nom + usb_us) / (1 - tick_share)
    bounded_pass = (setup_us + rx_bound + tx_bound + usb_us) / (1 - tick_share)
    print(f"  pass with the ticks' share ({tick_share:.0%}) taken out: nominal {nominal_pass / 1000:.2f} ms, worst "
          f"bounded {bounded_pass / 1000:.1f} ms")
    print(f"  so a command reaches the core <= {(nominal_pass + TICK_US) / 1000:.1f} ms after the module has it "
          f"(bounded {(bounded_pass + TICK_US) / 1000:.0f} ms), a telemetry frame reaches the module <= "
          f"{nominal_pass / 1000:.1f} ms after its tick, the spindle steps with a reading <= "
          f"{(10_000 + nominal_pass) / 1000:.1f} ms old")
    print("  left unbounded: WiFiNINA's wait for the module inside a call, after the command went out; a module that")
    print("  hangs there stops the background loop: the tick lands the rope on heartbeat loss, then stops feeding")
    print("  the watchdog (reset 250 ms later).")
    print()
    print(f"verdict: {'meets' if ok else 'MISSES'} the target: no tick over its {TICK_US} us period, ESC update "
          f"jitter < {JITTER_TARGET_US:.0f} us on every path" + ("" if ok else f" (missed on: {', '.join(missed)}; a "
          "tick past its period is counted in tick_overruns and delays the next tick's ESC update by the excess)"))


if __name__ == "__main__":
    main()
