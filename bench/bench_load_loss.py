"""Load-loss detection of the flying rope: what the drive can and cannot see, in figures.

Prints (never asserts):
  1. physics of the drive plant (steady state, drive_params.py): for free-loop and object loads, the ESC pulse,
     the throttle the feed-forward does not give (the PI integral), that as drive voltage, and as the monitor's
     force estimate; what a free-loop break removes (drag only, or the whole rope leaving the nip);
  2. SIL, the default monitor (load_loss_drop_n 1 N, load_loss_time_s 0.1 s): rope breaks under loads of
     0.5-5 N at 5 and 15 m/s: detected or not, latency from the break, the drop the device reported;
  3. SIL noise floor: the smallest load_loss_drop_n that raises no false alarm over 4 s of steady flight after
     the spin-up (the settling of the PI after a step is the largest disturbance);
  4. SIL, a harsh sequence (spin-up to 20 m/s, six speed steps, 3 N and 6 N loads coming on, a step under load,
     a battery sag of 12 V to 9.4 V in 50 ms for 0.5 s) over seeds: false alarms by threshold;
  5. Cortex-M0+ cost (unicorn, the ARM tick harness of bench_tick_instructions.py driven 1 s into steady
     flight, where the monitor judges): instructions and modelled cycles of the load-loss step (every 10 ms,
     in the spindle's slot) and of the tick it runs in.

Run:  uv run python bench/bench_load_loss.py [--quick]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import EventKind
from robowrangler_sim.plants.drive import kv_throttle_for_speed, steady_battery_v, steady_throttle_for_speed
from robowrangler_sim.plants.drive_params import DriveParams
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.plant_faults import BatterySag, RopeBreak
from robowrangler_sim.sil.scripted_host import ScriptedHost

P = gen.PARAMS_BY_NAME


def n_per_v(params: DriveParams, resistance_ohm: float = 0.085) -> float:
    """The monitor's scale: motor_count Kt / (R r), N/V (R: the drive_resistance_ohm parameter)."""
    return params.motor_count * params.torque_constant_nm_per_a / (resistance_ohm * params.wheel_radius_m)


def physics() -> None:
    p = DriveParams()
    scale = n_per_v(p)
    print(f"1. drive physics (plant steady state); monitor scale n Kt / (R r) = {scale:.2f} N/V")
    print(f"   {'v m/s':>6} {'load N':>7} {'pulse us':>9} {'integral':>9} {'I R mV':>7} {'estimate N':>10}")
    for v in (5.0, 15.0):
        for load in (0.0, 0.16, 0.5, 1.0, 2.0, 5.0):
            th = steady_throttle_for_speed(p, v, external_rope_load_n=load)
            vb = steady_battery_v(p, v, external_rope_load_n=load)
            resid = th - kv_throttle_for_speed(p, v, battery_v=vb)
            print(f"   {v:6.1f} {load:7.2f} {1000 + 1000 * th:9.2f} {resid:9.5f} {resid * vb * 1000:7.1f}"
                  f" {resid * vb * scale:10.2f}")
    no_drag = dataclasses.replace(p, rope_exposed_length_m=0.0)
    no_rope = dataclasses.replace(no_drag, guide_friction_n=0.0, nip_friction_n=0.0, nip_viscous_n_s_per_m=0.0)
    for v in (5.0, 15.0):
        full = steady_throttle_for_speed(p, v)
        drag_us = 1000 * (full - steady_throttle_for_speed(no_drag, v))
        rope_us = 1000 * (full - steady_throttle_for_speed(no_rope, v))
        print(f"   free-loop break at {v:4.1f} m/s: drag only {drag_us:.2f} us, whole rope out of the nip"
              f" {rope_us:.2f} us of pulse")
    print("   (the estimate's offset at zero load is the ESC dead band and motor friction; only changes are judged)")


def break_under(load_n: float, speed_mmps: int, *, drop_n: float | None = None) -> tuple[bool, float, float]:
    """(detected, latency s, reported drop N) for a RopeBreak 1 s after the load came on in settled flight."""
    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        if drop_n is not None:
            host.command(gen.ParamSet(P["load_loss_drop_n"].id, drop_n))
        host.arm_and_spin(speed_mmps, settle_s=1.5)
        sil.set_rope_load(load_n)
        host.run_for(1.0)
        t0_s = sil.time_s
        RopeBreak(start_s=t0_s).install(sil)
        host.run_for(1.5)
        lost = [e for e in host.received.events if e.event == EventKind.LOAD_LOST]
        host.close()
    if not lost:
        return False, math.nan, math.nan
    return True, lost[0].time_ms / 1000 - t0_s, lost[0].arg / 1000


def detection(quick: bool) -> None:
    print("2. SIL rope breaks, default monitor (drop 1 N for 0.1 s)")
    for speed in ((5000,) if quick else (5000, 15000)):
        for load in ((0.5, 1.5, 5.0) if quick else (0.5, 1.0, 1.2, 1.5, 2.0, 3.0, 5.0)):
            seen, latency_s, drop = break_under(load, speed)
            what = f"detected after {latency_s * 1000:5.0f} ms, reported drop {drop:.2f} N" if seen else "not detected"
            print(f"   {speed / 1000:4.1f} m/s, {load:4.1f} N: {what}")


def noise_floor(quick: bool) -> None:
    print("3. SIL: false alarms over 4 s of steady flight after the spin-up, by threshold")
    for speed in ((5000,) if quick else (3000, 5000, 15000, 20000)):
        row = []
        for drop_n in (0.05, 0.1, 0.2, 0.3, 0.5):
            with SilSession(speedup=None) as sil:
                host = ScriptedHost(sil)
                host.run_for(0.6)
                host.command(gen.ParamSet(P["load_loss_drop_n"].id, drop_n))
                host.arm_and_spin(speed, settle_s=1.5)
                host.run_for(4.0)
                alarms = sum(e.event == EventKind.LOAD_LOST for e in host.received.events)
                host.close()
            row.append(f"{drop_n:.2f} N: {'ALARM' if alarms else 'quiet'}")
        print(f"   {speed / 1000:4.1f} m/s  " + ", ".join(row))


def harsh(quick: bool) -> None:
    print("4. SIL: false alarms over spin-up, steps, loads and a fast sag (seeds), by threshold")
    for drop_n in (0.3, 0.5, 1.0):
        alarms = []
        for seed in range(2 if quick else 5):
            with SilSession(speedup=None, seed=seed) as sil:
                host = ScriptedHost(sil)
                host.run_for(0.6)
                host.command(gen.ParamSet(P["load_loss_drop_n"].id, drop_n))
                host.arm_and_spin(20000, settle_s=2.0)
                for mmps in (4000, 12000, 3100, 8000, 20000, 3000):
                    host.command(gen.SetRopeSpeed(mmps))
                    host.run_for(1.5)
                sil.set_rope_load(3.0)
                host.run_for(1.0)
                sil.set_rope_load(6.0)
                host.run_for(1.0)
                host.command(gen.SetRopeSpeed(5000))
                host.run_for(1.5)
                BatterySag(start_s=sil.time_s, target_v=9.4, ramp_s=0.05, duration_s=0.5).install(sil)
                host.run_for(1.5)
                alarms.append(sum(e.event == EventKind.LOAD_LOST for e in host.received.events))
                host.close()
        print(f"   {drop_n:.1f} N: false alarms per seed {alarms}")


def m0_cost() -> None:
    print("5. Cortex-M0+ cost of the load-loss step, steady flight at 5 m/s (unicorn, modelled cycles)")
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    try:
        import bench_tick_instructions as tick_bench
        emu = tick_bench.ah.HarnessEmulator(tick_bench.ah.build_arm())
    except Exception as err:  # no ARM toolchain or unicorn here: say so, measure nothing
        print(f"   not measured: {type(err).__name__}: {err}")
        return
    scenario = tick_bench.Scenario(emu)
    scenario.to_airborne()
    scenario.run_quiet(1000)  # past the monitor's learning time: it judges from here
    rows = []
    for _ in range(40):
        scenario.now_us += 1000
        _, prof = emu.tick(scenario.now_us, count=True, inclusive_roots=("rw_core_load_loss_step",))
        if prof.inclusive["rw_core_load_loss_step"]:  # the 10 ms slot it shares with the spindle step
            rows.append((prof.inclusive["rw_core_load_loss_step"], prof.inclusive_cycles["rw_core_load_loss_step"],
                         prof.cycles))
    assert rows, "no load-loss step in 40 ticks (it runs every 10 ms)"
    instr, cycles, tick_cycles = max(rows, key=lambda r: r[1])
    print(f"   load-loss step {instr} instructions, {cycles} cycles ({100 * cycles / 48_000:.1f} % of a 1 ms tick at"
          f" 48 MHz), every 10 ms in the spindle's slot; that whole tick {tick_cycles} cycles "
          f"({100 * tick_cycles / 48_000:.1f} %)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer speeds and loads")
    args = parser.parse_args()
    physics()
    detection(args.quick)
    noise_floor(args.quick)
    harsh(args.quick)
    m0_cost()


if __name__ == "__main__":
    main()
