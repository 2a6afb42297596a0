"""Instructions and Cortex-M0+ cycles of one control tick of the firmware core, emulated with unicorn.

Builds the ARM harness (firmware/cmake/arm_tick_harness.c, -mcpu=cortex-m0plus -Os) if needed, drives the
core through its fake HAL to AIRBORNE (ARM, HOME by the limit switch, SET_ROPE_SPEED 5 m/s, wheel turning at
the matching speed, heartbeats, then SET_LOOP so the spindle position loop is moving the guide), then profiles
single rw_core_tick calls:

  1. the periodic schedule: SCHEDULE_TICKS consecutive ticks with nothing received, each labelled by what ran
     in it (TICK_PARTS: speed loop, spindle step + load-loss check, telemetry pack, the steps signing a queued
     frame over idle ticks: begin / absorb / finish + send); the worst tick of each kind, the mean, and the
     verdict against the target: every periodic tick under 10 % of a 1 kHz tick (4,800 modelled cycles);
  2. a datagram received at each of PHASES consecutive schedule phases, worst tick of each kind: a command
     (SET_ROPE_SPEED: tag check, execution, the ACK signed at once), PARAM_SET (+ event and PARAM_VALUE
     queued, parameters re-applied), a HEARTBEAT (no reply), a replayed and a forged command (dropped
     unanswered after the tag check);
  3. a 1000-sample burst (BURST_START): the ticks while it samples and while its frames stream out, by kind;
  4. rw_siphash24 alone on the signed part of typical frames (SET_ROPE_SPEED, ACK, TELEMETRY).

The link is signed (protocol v2): the harness's fake flash holds the test key, every host frame is signed
for the session with a growing counter, and every frame the core sends over WiFi is checked to be signed.
"MAC cyc" is what a tick spent inside rw_frame_tag_valid, rw_frame_sign and the rw_signer steps, callees
included. Prints instructions, modelled cycles (see tests/firmware_arm/arm_harness_emulator.py for the
Cortex-M0+ cycle model) and the CPU load at 1 kHz on 48 MHz, then what dominates the heaviest ticks per
function and per group (soft-float, CRC, memcpy/memset, integer division, codec, MAC, core, fake HAL).

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
LOOP_TARGET_UM = 150_000  # far from home: the spindle keeps moving while the ticks are profiled
SCHEDULE_TICKS = 200  # ten telemetry periods (20 ms at 50 Hz), twenty spindle periods (10 ms)
PHASES = 20  # a received datagram at each of this many consecutive ticks (one telemetry period)
# The SAMD21 runs its flash at 48 MHz with one wait state, partly hidden by its cache: real cycles lie between
# the modelled count and this factor times it (DESIGN.md); the budget is checked against the upper bound too.
FLASH_WAIT_FACTOR = 1.5


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
        return "CRC-16 (table)"
    if func.startswith(("rw_siphash", "rw_signer_", "sip_")) or func in ("compress", "load_le32", "finalize_rounds"):
        return "SipHash-2-4 (MAC)"
    if func in ("__aeabi_llsl", "__aeabi_llsr", "__aeabi_lasr", "__ashldi3", "__lshrdi3", "__ashrdi3"):
        return "64-bit shifts (libgcc)"
    if func in ("memcpy", "memset", "memmove"):
        return "memcpy/memset"
    if func.startswith(("rw_msg_", "rw_frame_")):
        return "protocol codec (pack/unpack/frame)"
    if func.startswith(("fake_", "harness_")):
        return "fake HAL (harness)"
    return "core logic"


MAC_ROOTS = ("rw_frame_tag_valid", "rw_frame_sign", "rw_signer_begin_prepared", "rw_signer_absorb", "rw_signer_finish")

# What ran in a tick, by the functions it executed (each is in its own translation unit: never inlined).
TICK_PARTS = (
    ("speed", "rw_pi_controller_step"),
    ("spindle", "rw_spindle_step"),
    ("telemetry pack", "rw_msg_telemetry_pack"),
    ("battery", "rw_throttle_map_prepare_battery"),
    ("load check", "rw_load_monitor_step_q16"),
    ("mac begin", "rw_signer_begin_prepared"),
    ("mac absorb", "rw_signer_absorb"),
    ("mac finish+send", "rw_signer_finish"),
    ("rx verify", "rw_frame_tag_valid"),
    ("reply sign", "rw_frame_sign"),
    ("burst pack", "rw_msg_burst_data_pack"),
)


def tick_label(profile: "ah.CallProfile") -> str:
    """The parts of the schedule that ran in a profiled tick, e.g. 'speed' or 'mac absorb'."""
    return " + ".join(part for part, func in TICK_PARTS if profile.per_function.get(func)) or "none"


class Scenario:
    """Drives the emulated core with a 1 ms tick clock and host frames signed for its session."""

    def __init__(self, emu: ah.HarnessEmulator) -> None:
        self.emu = emu
        self.now_us = 0
        self.host = ah.SignedHost()

    def frame(self, message) -> bytes:  # noqa: ANN001
        """message signed with the test key for session 1 (the harness's first boot), next seq and counter."""
        return self.host.frame(message)

    def tick(self, datagram: bytes | None = None, *, count: bool = False):  # noqa: ANN201
        self.now_us += 1000
        if datagram is not None:
            self.emu.put_datagram(datagram)
        sent, profile = self.emu.tick(self.now_us, count=count, inclusive_roots=MAC_ROOTS if count else ())
        out = []
        for _, raw in sent:
            frame, msg = proto.decode_message(raw)
            assert frame.signed and proto.tag_valid(frame, ah.TEST_KEY), f"the core sent an unsigned or bad frame: {msg}"
            out.append(msg)
        return out, profile

    def run_quiet(self, ticks: int) -> list:
        out = []
        for i in range(ticks):
            hb = self.frame(proto.Heartbeat(host_time_ms=self.now_us // 1000)) if i % 100 == 99 else None
            sent, _ = self.tick(hb)
            out.extend(sent)
        return out

    def to_airborne(self) -> None:
        self.emu.reset()
        self.run_quiet(1)
        assert self.emu.session_id() == self.host.session_id, "the harness's first boot must be session 1"
        self.run_quiet(599)  # arming hold (arm_hold_s) with heartbeats
        sent, _ = self.tick(self.frame(proto.Arm()))
        assert sent and isinstance(sent[0], proto.Ack), f"ARM not acknowledged: {sent}"
        sent, _ = self.tick(self.frame(proto.Home()))
        assert sent and isinstance(sent[0], proto.Ack), f"HOME not acknowledged: {sent}"
        self.emu.write_u32("harness_spindle_switch", 1)  # the guide reaches the home switch
        self.run_quiet(30)
        self.emu.write_u32("harness_spindle_switch", 0)
        rpm = round(TARGET_MMPS * 1e-3 / (2 * math.pi * WHEEL_RADIUS_M) * 60)
        self.emu.set_wheel_rpm(rpm)
        sent, _ = self.tick(self.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS)))
        assert sent and isinstance(sent[0], proto.Ack), f"SET_ROPE_SPEED not acknowledged: {sent}"
        for _ in range(2000):
            self.run_quiet(1)
            if self.emu.state() == proto.State.AIRBORNE:
                break
        assert self.emu.state() == proto.State.AIRBORNE, f"not airborne: state {self.emu.state()}"
        sent, _ = self.tick(self.frame(proto.SetLoop(guide_position_um=LOOP_TARGET_UM)))
        assert sent and isinstance(sent[0], proto.Ack), f"SET_LOOP not acknowledged: {sent}"
        self.run_quiet(200)  # drain the event queue, settle the loop

    def schedule_cycle(self, ticks: int) -> list[tuple[str, "ah.CallProfile"]]:
        """Profile `ticks` consecutive ticks with nothing received; each with a label of what ran in it."""
        out = []
        for _ in range(ticks):
            _, profile = self.tick(None, count=True)
            out.append((tick_label(profile), profile))
        return out

    def until_telemetry_message(self) -> "proto.Telemetry":
        """Tick until a tick sends TELEMETRY; returns the message."""
        for _ in range(200):
            sent, _ = self.tick(None)
            for m in sent:
                if isinstance(m, proto.Telemetry):
                    return m
        raise RuntimeError("no telemetry within 200 ticks")


def profile_row(name: str, p: "ah.CallProfile") -> str:
    cycles_per_tick = CPU_HZ / TICK_HZ
    us = p.cycles / CPU_HZ * 1e6
    mac_cycles = sum(p.inclusive_cycles[r] for r in MAC_ROOTS)
    return (f"{name:<34}{p.instructions:>8}{p.cycles:>8}{us:>8.1f}{p.cycles / cycles_per_tick:>9.1%}"
            f"{FLASH_WAIT_FACTOR * p.cycles / cycles_per_tick:>9.1%}{p.stack_bytes:>8}{mac_cycles:>8}")


def print_breakdown(title: str, p: "ah.CallProfile") -> None:
    print(f"{title}: instructions by group:")
    groups: Counter = Counter()
    for func, n in p.per_function.items():
        groups[group_of(func)] += n
    for g, n in groups.most_common():
        print(f"  {g:<38}{n:>7}  {n / p.instructions:6.1%}")
    print("  top functions:")
    for func, n in p.per_function.most_common(8):
        print(f"    {func:<36}{n:>7}  {n / p.instructions:6.1%}")
    print("  runtime-library instructions (soft-float, division, memcpy) by calling function:")
    for func, n in p.runtime_by_caller.most_common(6):
        print(f"    {func:<36}{n:>7}  {n / p.instructions:6.1%}")


def main() -> None:
    elf = ah.build_arm()
    emu = ah.HarnessEmulator(elf)
    sc = Scenario(emu)
    sc.to_airborne()

    # 1. The periodic work: SCHEDULE_TICKS consecutive ticks, nothing received.
    cycle = sc.schedule_cycle(SCHEDULE_TICKS)
    assert emu.state() == proto.State.AIRBORNE
    by_label: dict[str, list["ah.CallProfile"]] = {}
    for label, profile in cycle:
        by_label.setdefault(label, []).append(profile)
    worst_label, worst_periodic = max(cycle, key=lambda item: item[1].cycles)

    # 2. A received datagram at every phase of the schedule (PHASES consecutive ticks): the worst tick of each
    # kind. A command is verified, executed and ACKed (the ACK signed in one piece) in the tick it arrives.
    kp = proto.PARAMS_BY_NAME["speed_kp"]
    kinds = {
        "command (SET_ROPE_SPEED + ACK)": lambda: sc.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS)),
        "param_set (+ ACK, event, value)": lambda: sc.frame(proto.ParamSet(param_id=kp.id, value=kp.default)),
        "heartbeat (no reply)": lambda: sc.frame(proto.Heartbeat(host_time_ms=sc.now_us // 1000)),
    }
    rx_worst: dict[str, tuple[str, "ah.CallProfile"]] = {}
    for name, make in kinds.items():
        for _ in range(PHASES):
            sent, profile = sc.tick(make(), count=True)
            if name != "heartbeat (no reply)":
                assert sent and isinstance(sent[0], proto.Ack), f"{name}: {sent}"
            if name not in rx_worst or profile.cycles > rx_worst[name][1].cycles:
                rx_worst[name] = (tick_label(profile), profile)
    accepted = sc.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS))
    sent, _ = sc.tick(accepted)
    assert sent and isinstance(sent[0], proto.Ack), f"SET_ROPE_SPEED not acknowledged: {sent}"
    for name in ("replayed (dropped)", "forged (dropped)"):
        for _ in range(PHASES):
            if name.startswith("replayed"):
                frame = accepted
            else:
                forged = bytearray(sc.frame(proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS)))
                forged[-1] ^= 0x01
                frame = bytes(forged)
            sent, profile = sc.tick(frame, count=True)
            assert not any(isinstance(m, (proto.Ack, proto.Nack)) for m in sent), f"{name} was answered: {sent}"
            if name not in rx_worst or profile.cycles > rx_worst[name][1].cycles:
                rx_worst[name] = (tick_label(profile), profile)
    sc.run_quiet(40)
    last_telemetry = sc.until_telemetry_message()
    assert last_telemetry.rx_replayed == PHASES and last_telemetry.rx_auth_failed == PHASES, last_telemetry
    assert emu.state() == proto.State.AIRBORNE

    # 3. A burst (BURST_START, 1000 samples): every tick samples for 1 s, then the frames stream out; the periodic
    # ticks of both phases profiled (the tick that takes the command is a command tick, as in 2).
    sent, _ = sc.tick(sc.frame(proto.BurstStart(samples=1000)))
    assert sent and isinstance(sent[0], proto.Ack), f"BURST_START not acknowledged: {sent}"
    burst_cycle = []  # capture, then the first 200 ticks of the stream; a heartbeat every 100 ticks (not profiled)
    for i in range(1000 + 200):
        if i % 100 == 99:
            sc.tick(sc.frame(proto.Heartbeat(host_time_ms=sc.now_us // 1000)))
            continue
        _, profile = sc.tick(None, count=True)
        burst_cycle.append((tick_label(profile), profile))
    burst_by_label: dict[str, list["ah.CallProfile"]] = {}
    for label, profile in burst_cycle:
        burst_by_label.setdefault(label, []).append(profile)
    burst_worst_label, burst_worst = max(burst_cycle, key=lambda item: item[1].cycles)
    assert emu.state() == proto.State.AIRBORNE, f"not airborne during the burst: state {emu.state()}"

    cycles_per_tick = CPU_HZ / TICK_HZ
    print(f"ELF: {elf}")
    print(f"rw_core_tick on Cortex-M0+ (unicorn), AIRBORNE at {TARGET_MMPS} mm/s, spindle moving, signed link, "
          f"{CPU_HZ / 1e6:.0f} MHz, {TICK_HZ} Hz tick")
    print("cycle model: ALU 1, load/store 2, LDM/STM/PUSH/POP 1+N, branch taken 2 (BL 3), zero flash wait states;")
    print("             SAMD21 flash at 48 MHz has 1 wait state: real cycles up to ~1.5x the modelled figure.")
    print("target: every tick of the periodic schedule under 10 % of a 1 kHz tick (4,800 modelled cycles)")
    header = (f"{'tick':<34}{'instr':>8}{'cycles':>8}{'us':>8}{'load':>9}{'x1.5':>9}{'stack B':>8}"
              f"{'MAC cyc':>8}")
    print(f"\n1. periodic schedule, {SCHEDULE_TICKS} consecutive ticks, nothing received: worst tick of each kind")
    print(header)
    for label, profiles in sorted(by_label.items(), key=lambda kv: -max(p.cycles for p in kv[1])):
        worst = max(profiles, key=lambda p: p.cycles)
        print(profile_row(f"{label} (x{len(profiles)})", worst))
    mean_cycles = sum(p.cycles for _, p in cycle) / len(cycle)
    print(f"{'mean over the cycle':<34}{'':>8}{mean_cycles:>8.0f}{mean_cycles / CPU_HZ * 1e6:>8.1f}"
          f"{mean_cycles / cycles_per_tick:>9.1%}{FLASH_WAIT_FACTOR * mean_cycles / cycles_per_tick:>9.1%}")
    verdict = "meets" if worst_periodic.cycles < 0.1 * cycles_per_tick else "MISSES"
    print(f"worst periodic tick: '{worst_label}', {worst_periodic.cycles} cycles = "
          f"{worst_periodic.cycles / cycles_per_tick:.1%} at 1 kHz: {verdict} the 10 % target")
    worst_1_5 = FLASH_WAIT_FACTOR * worst_periodic.cycles
    verdict_1_5 = "meets" if worst_1_5 < 0.1 * cycles_per_tick else "MISSES"
    print(f"worst periodic tick with one flash wait state (x{FLASH_WAIT_FACTOR}): {worst_1_5:.0f} cycles = "
          f"{worst_1_5 / cycles_per_tick:.1%} at 1 kHz: {verdict_1_5} the 10 % target")

    print("\n3. a 1000-sample burst: 1,000 ticks sampling, then 200 ticks of its stream (nothing received)")
    print(header)
    for label, profiles in sorted(burst_by_label.items(), key=lambda kv: -max(p.cycles for p in kv[1])):
        worst = max(profiles, key=lambda p: p.cycles)
        print(profile_row(f"{label} (x{len(profiles)})", worst))
    verdict = "meets" if burst_worst.cycles < 0.1 * cycles_per_tick else "MISSES"
    print(f"worst tick with a burst: '{burst_worst_label}', {burst_worst.cycles} cycles = "
          f"{burst_worst.cycles / cycles_per_tick:.1%} at 1 kHz: {verdict} the 10 % target")

    print(f"\n2. a datagram received, worst over {PHASES} consecutive schedule phases (label = what else ran)")
    print(header)
    for name, (label, p) in rx_worst.items():
        print(profile_row(name, p) + f"   [{label}]")
    print("  MAC cyc = inside rw_frame_tag_valid (verify), rw_frame_sign (the ACK) and rw_signer_* (queued frames)")

    print("\nrw_siphash24 alone (key in flash, message in RAM), on the bytes a tag covers:")
    print(f"{'message':<34}{'bytes':>6}{'instructions':>13}{'cycles':>9}{'us @48MHz':>11}{'cycles/B':>10}")
    typical = (
        ("SET_ROPE_SPEED (host command)", proto.SetRopeSpeed(rope_speed_mmps=TARGET_MMPS)),
        ("ACK (device reply)", proto.Ack(cmd_msg_id=proto.SetRopeSpeed.MSG_ID, cmd_seq=1, state=proto.State.AIRBORNE)),
        ("TELEMETRY (device, 50 Hz)", last_telemetry),
    )
    for label, message in typical:
        signed = proto.decode_frame(proto.encode_frame(message, 1, key=ah.TEST_KEY, session_id=1, counter=1)).signed_bytes
        tag, p = emu.siphash(signed, count=True)
        assert tag.to_bytes(8, "little") == proto.siphash24(ah.TEST_KEY, signed), "ARM SipHash differs from Python"
        print(f"{label:<34}{len(signed):>6}{p.instructions:>13}{p.cycles:>9}{p.cycles / CPU_HZ * 1e6:>11.1f}"
              f"{p.cycles / len(signed):>10.1f}")

    print()
    print_breakdown(f"heaviest periodic tick ('{worst_label}')", worst_periodic)
    rx_name = max(rx_worst, key=lambda k: rx_worst[k][1].cycles)
    print_breakdown(f"heaviest tick with a datagram ({rx_name})", rx_worst[rx_name][1])
    speed = max(by_label.get("speed", [worst_periodic]), key=lambda p: p.cycles)
    print_breakdown("speed tick", speed)


if __name__ == "__main__":
    main()
