"""Instructions and Cortex-M0+ cycles of one control tick of the firmware core, emulated with unicorn.

Builds the ARM harness (firmware/cmake/arm_tick_harness.c, -mcpu=cortex-m0plus -Os) if needed, drives the
core through its fake HAL to AIRBORNE (ARM, SET_ROPE_SPEED 5 m/s, wheel turning at the matching speed,
heartbeats), then profiles single rw_core_tick calls:

  quiet        AIRBORNE, speed loop active, nothing received, no telemetry due
  telemetry    the same, telemetry packed and sent
  command      SET_ROPE_SPEED received, decoded, executed and ACKed, telemetry packed (queued: the core sends
               at most one datagram per tick, so the ACK goes out and the telemetry in the next tick)
  param_set    PARAM_SET received and ACKed, PARAM_CHANGED event and PARAM_VALUE queued, parameters re-applied,
               telemetry packed (the heaviest path found)
  heartbeat    HEARTBEAT received and accepted (no reply), telemetry packed and sent in the same tick: the
               one path on which a received datagram and an outgoing telemetry frame share a tick

Prints instructions, modelled cycles (see tests/firmware_arm/arm_harness_emulator.py for the Cortex-M0+ cycle
model) and the CPU load of that tick at 1 kHz on 48 MHz, then what dominates the heaviest tick per function
and per group (soft-float, CRC, memcpy/memset, integer division, codec, core, fake HAL).

    uv run python bench/bench_tick_instructions.py
"""

from __future__ import annotations

import math
import sys
from collections import Counter
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT / "tests" / "firmware_arm"))

import arm_harness_emulator as ah  # noqa: E402
from robowrangler.protocol import generated as proto  # noqa: E402

CPU_HZ = 48_000_000
TICK_HZ = 1000
TARGET_MMPS = 5000
WHEEL_RADIUS_M = 0.015


def group_of(func: str) -> str:
    """The cost group a function belongs to."""
    if func.startswith(("__aeabi_f", "__aeabi_i2f", "__aeabi_ui2f", "__gtsf2", "__gesf2", "__ltsf2", "__lesf2",
                        "__eqsf2", "__nesf2", "__unordsf2", "__fixunssf", "__fixsf", "__floatsisf", "__floatunsisf",
                        "__addsf3", "__subsf3", "__mulsf3", "__divsf3", "__clzsi2", "floorf", "ceilf")):
        return "soft-float (libgcc/libm)"
    if func.startswith("__aeabi_d") or func.endswith("df2") or func.endswith("df3"):
        return "soft-double (should be none)"
    if func in ("__udivsi3", "__aeabi_uidiv", "__aeabi_uidivmod", "__divsi3", "__aeabi_idiv", "__aeabi_idivmod"):
        return "integer division"
    if func == "rw_crc16_ccitt":
        return "CRC-16 (bitwise)"
    if func in ("memcpy", "memset", "memmove"):
        return "memcpy/memset"
    if func.startswith(("rw_msg_", "rw_frame_")):
        return "protocol codec (pack/unpack/frame)"
    if func.startswith(("fake_", "harness_")):
        return "fake HAL (harness)"
    return "core logic"


class Scenario:
    """Drives the emulated core with a 1 ms tick clock and host frames."""

    def __init__(self, emu: ah.HarnessEmulator) -> None:
        self.emu = emu
        self.now_us = 0
        self.seq = 0

    def frame(self, message) -> bytes:  # noqa: ANN001
        self.seq += 1
        return proto.encode_frame(message, self.seq)

    def tick(self, datagram: bytes | None = None, *, count: bool = False):  # noqa: ANN201
        self.now_us += 1000
        if datagram is not None:
            self.emu.put_datagram(datagram)
        sent, profile = self.emu.tick(self.now_us, count=count)
        return [proto.decode_message(raw)[1] for _, raw in sent], profile

    def run_quiet(self, ticks: int) -> list:
        out = []
        for i in range(ticks):
            hb = self.frame(proto.Heartbeat(host_time_ms=self.now_us // 1000)) if i % 100 == 99 else None
            sent, _ = self.tick(hb)
            out.extend(sent)
        return out

    def to_airborne(self) -> None:
        self.emu.reset()
        self.run_quiet(600)  # arming hold (arm_hold_s) with heartbeats
        sent, _ = self.tick(self.frame(proto.Arm()))
        assert sent and isinstance(sent[0], proto.Ack), f"ARM not acknowledged: {sent}"
        rpm = round(TARGET_MMPS * 1e-3 / (2 * math.pi * WHEEL_RADIUS_M) * 60)
        self.emu.set_wheel_rpm(rpm)
        sent, _ = self.tick(self.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS)))
        assert sent and isinstance(sent[0], proto.Ack), f"SET_ROPE_SPEED not acknowledged: {sent}"
        for _ in range(2000):
            self.run_quiet(1)
            if self.emu.state() == proto.State.AIRBORNE:
                break
        assert self.emu.state() == proto.State.AIRBORNE, f"not airborne: state {self.emu.state()}"
        self.run_quiet(200)  # drain the event queue, settle the loop

    def until_telemetry(self):  # noqa: ANN201
        """Tick (profiled) until a tick sends TELEMETRY; returns that tick's profile."""
        for _ in range(200):
            sent, profile = self.tick(None, count=True)
            if any(isinstance(m, proto.Telemetry) for m in sent):
                return profile
        raise RuntimeError("no telemetry within 200 ticks")


def main() -> None:
    elf = ah.build_arm()
    emu = ah.HarnessEmulator(elf)
    sc = Scenario(emu)
    sc.to_airborne()
    period_ms = round(1000 / proto.PARAMS_BY_NAME["telemetry_rate_hz"].default)

    results: dict[str, ah.CallProfile] = {}
    results["telemetry"] = sc.until_telemetry()
    sent, results["quiet"] = sc.tick(None, count=True)
    assert not sent, f"quiet tick sent {sent}"
    sc.run_quiet(period_ms - 2)  # the next tick is due for telemetry
    sent, results["command"] = sc.tick(sc.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS + 100)), count=True)
    assert sent and isinstance(sent[0], proto.Ack), f"command tick sent {sent}"
    sent, _ = sc.tick(None)
    assert sent and isinstance(sent[0], proto.Telemetry), f"telemetry was not packed in the command tick: {sent}"
    sc.run_quiet(period_ms - 2)
    kp = proto.PARAMS_BY_NAME["speed_kp"]
    sent, results["param_set"] = sc.tick(sc.frame(proto.ParamSet(param_id=kp.id, value=kp.default)), count=True)
    assert sent and isinstance(sent[0], proto.Ack), f"param_set tick sent {sent}"
    assert emu.state() == proto.State.AIRBORNE
    sc.run_quiet(5)  # PARAM_VALUE and the event leave
    sc.until_telemetry()
    sc.run_quiet(period_ms - 1)
    sent, results["heartbeat"] = sc.tick(sc.frame(proto.Heartbeat(host_time_ms=sc.now_us // 1000)), count=True)
    assert sent and isinstance(sent[0], proto.Telemetry), f"heartbeat tick sent {sent}"

    cycles_per_tick = CPU_HZ / TICK_HZ
    print(f"ELF: {elf}")
    print(f"rw_core_tick on Cortex-M0+ (unicorn), AIRBORNE at {TARGET_MMPS} mm/s, {CPU_HZ / 1e6:.0f} MHz, {TICK_HZ} Hz tick")
    print("cycle model: ALU 1, load/store 2, LDM/STM/PUSH/POP 1+N, branch taken 2 (BL 3), zero flash wait states;")
    print("             SAMD21 flash at 48 MHz has 1 wait state: real cycles up to ~1.5x the modelled figure.")
    print(f"{'tick':<11}{'instructions':>13}{'cycles':>9}{'us @48MHz':>11}{'load @1kHz':>12}{'load x1.5':>11}"
          f"{'stack B':>9}")
    for name in ("quiet", "telemetry", "heartbeat", "command", "param_set"):
        p = results[name]
        us = p.cycles / CPU_HZ * 1e6
        print(f"{name:<11}{p.instructions:>13}{p.cycles:>9}{us:>11.1f}{p.cycles / cycles_per_tick:>11.1%}"
              f"{1.5 * p.cycles / cycles_per_tick:>11.1%}{p.stack_bytes:>9}")

    worst_name = max(results, key=lambda k: results[k].cycles)
    worst = results[worst_name]
    print(f"\nheaviest tick: {worst_name}; instructions by group:")
    groups: Counter = Counter()
    for func, n in worst.per_function.items():
        groups[group_of(func)] += n
    for g, n in groups.most_common():
        print(f"  {g:<38}{n:>7}  {n / worst.instructions:6.1%}")
    print("top functions:")
    for func, n in worst.per_function.most_common(12):
        print(f"  {func:<38}{n:>7}  {n / worst.instructions:6.1%}")
    print("runtime-library instructions (soft-float, division, memcpy) by calling function, heaviest tick:")
    for func, n in worst.runtime_by_caller.most_common(8):
        print(f"  {func:<38}{n:>7}  {n / worst.instructions:6.1%}")
    print("quiet tick, instructions by group:")
    groups = Counter()
    for func, n in results["quiet"].per_function.items():
        groups[group_of(func)] += n
    for g, n in groups.most_common():
        print(f"  {g:<38}{n:>7}  {n / results['quiet'].instructions:6.1%}")
    print("quiet tick, runtime-library instructions by calling function:")
    for func, n in results["quiet"].runtime_by_caller.most_common(8):
        print(f"  {func:<38}{n:>7}  {n / results['quiet'].instructions:6.1%}")
    print("instruction classes (heaviest tick):", dict(worst.per_class))


if __name__ == "__main__":
    main()
