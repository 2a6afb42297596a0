"""Same scenario and seed -> identical telemetry, whatever the pacing."""

from __future__ import annotations

from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost


def run_scenario(*, speedup: float | None, seed: int) -> list[bytes]:
    with SilSession(speedup=speedup, seed=seed) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        host.send(gen.Arm())
        host.run_for(0.01)
        host.send(gen.SetRopeSpeed(4000))
        host.run_for(0.5)
        sil.set_rope_load(2.0)
        host.send(gen.SetRopeSpeed(6000))
        host.run_for(0.4)
        host.send(gen.Spindown())
        host.run_for(0.3)
        host.close()
        return [bytes(gen.encode_frame(t, 0)) for t in host.received.telemetry]


def test_same_seed_same_telemetry_at_any_speed(native_build_dir: Path) -> None:
    unpaced = run_scenario(speedup=None, seed=7)
    again = run_scenario(speedup=None, seed=7)
    paced = run_scenario(speedup=4.0, seed=7)
    assert len(unpaced) > 80
    assert unpaced == again
    assert unpaced == paced


def test_another_seed_changes_the_noise(native_build_dir: Path) -> None:
    assert run_scenario(speedup=None, seed=7) != run_scenario(speedup=None, seed=8)
