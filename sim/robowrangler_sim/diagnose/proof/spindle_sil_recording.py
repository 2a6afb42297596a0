"""A closed-loop spindle recording for the closed-loop before/after: the SIL firmware (the real core) drives a
SpindleTruthPlant (spindle_truth.py) in lockstep while a recorded host homes the spindle, spins the rope up and
moves the loop in and out (large moves and 1-2 mm reversals, as `wrangler excite --profile spindle` does); the
recording holds the telemetry and the /host/command records the closed-loop replay sends again.

    record_spindle_sil("r.mcap", truth={"deadband_in_raw": 90, "deadband_out_raw": 90}, seed=2)
"""

from __future__ import annotations

from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler.recorder import RecordingSession
from robowrangler_sim.diagnose.proof.spindle_truth import SpindleTruthPlant
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.recording_host import RecordingHost

LOOP_MOVES_MM = (8.0, 14.0, 12.0, 12.5, 12.0, 6.0, 7.0, 6.5, 10.0, 9.0, 9.5)


def record_spindle_sil(path: str | Path, *, truth: dict[str, float] | None, seed: int = 0, hold_s: float = 1.0,
                       moves_mm: tuple[float, ...] = LOOP_MOVES_MM) -> Path:
    path = Path(path)

    def spindle(params, *, seed):
        return SpindleTruthPlant(params, seed=seed, **(truth or {}))

    with SilSession(speedup=None, seed=seed, spindle=spindle) as sil, \
            RecordingSession(path, source="sil", time_base="simulation", seed=seed,
                             clock_ns=lambda: sil.plant.time_us * 1000,
                             description=f"closed-loop spindle run, truth {truth}") as rec:
        host = RecordingHost(sil, rec)
        host.command_accepted(gen.ParamSet(gen.PARAMS_BY_NAME["homing_speed_mmps"].id, 15.0))
        # a tight tolerance: the loop ends each move with small commands, where a servo dead band shows
        host.command_accepted(gen.ParamSet(gen.PARAMS_BY_NAME["spindle_tolerance_mm"].id, 0.1))
        host.command_accepted(gen.Home())
        host.run_until(lambda h: any(e.event == gen.EventKind.SPINDLE_HOMED for e in h.received.events),
                       timeout_s=30.0)
        host.arm_and_spin(5000, settle_s=1.0)
        for mm in moves_mm:
            host.command_accepted(gen.SetLoop(int(round(mm * 1000))))
            host.run_for(hold_s)
        rec.close(host_s=sil.time_s)
    return path
