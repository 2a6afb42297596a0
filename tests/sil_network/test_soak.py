"""Soak: seeded random valid and invalid commands (and unsigned, forged and replayed frames) through a bursty,
lossy, duplicating, reordering and corrupting signed link (plus total blackouts), every invariant checked
at every tick (see soak_runner).

CI runs 30 simulated seconds (a few seconds of wall time); bench/bench_soak.py runs 30 minutes.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from link_gate import seeded_key
from soak_runner import Soak, SoakConfig, run_soak

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.impairment import ImpairmentConfig, LinkImpairment
from robowrangler_sim.sil.scripted_host import ScriptedHost

GUARD_MMPS = 2990  # tov_mps x tov_margin, defaults


def test_short_soak_under_impairment_keeps_every_invariant(native_build_dir: Path) -> None:
    f = run_soak(SoakConfig(duration_s=30.0, seed=1))
    assert f.violations == 0, "\n".join(f.first_violations)
    assert f.ticks_checked == 30_000 and f.telemetry_checked > 1400
    # it exercised what it claims to check
    assert f.commands_executed > 80 and f.commands_accepted > 40 and f.commands_refused > 20
    assert f.malformed_sent > 0 and f.retransmissions > 10 and f.duplicates_answered > 5
    assert f.forged_sent > 0 and f.replays_sent > 0  # frames the device must drop unanswered
    assert f.auth_failed_dropped > 0 and f.replays_dropped > 5  # ... and its counters were checked against them
    assert f.airborne_ticks > 0.3 * f.ticks_checked and f.min_airborne_margin_mps > -0.3
    assert f.blackouts == 2 and f.heartbeat_losses >= 1  # (no HEARTBEAT_LOST in a blackout while DISARMED)
    for direction in ("to_device", "to_host"):
        c = f.proxy[direction]
        assert c["dropped_in_bad_state"] > 0 and c["duplicated"] > 0 and c["corrupted"] > 0 and c["reordered"] > 0
    assert f.host_frames_missing > 100 and f.host_frames_stale > 10


def test_soak_is_deterministic(native_build_dir: Path) -> None:
    def figures(seed: int) -> dict:
        f = vars(run_soak(SoakConfig(duration_s=5.0, seed=seed, blackout_every_s=4.0)))
        f.pop("wall_s")
        return f
    first = figures(4)
    assert first == figures(4)
    assert first != figures(5)


def test_soak_config_is_checked() -> None:
    with pytest.raises(ValueError, match="^duration_s: expected"):
        SoakConfig(duration_s=0)
    with pytest.raises(ValueError, match="^command_gap_s: expected"):
        SoakConfig(command_gap_s=(0.5, 0.1))
    with pytest.raises(ValueError, match="^blackout_s: expected"):
        SoakConfig(blackout_s=20.0, blackout_every_s=10.0)


def test_the_checker_flags_what_it_must(native_build_dir: Path) -> None:
    """Device frames the checker must object to: a LOOP_COLLAPSED with nothing loading the rope, a late
    HEARTBEAT_LOST, an rx_duplicates that does not match the repeats answered, an ACK for garbage, a verdict
    for a replayed frame (it acted on it), rx_replayed and rx_auth_failed that miss a drop, an unsigned frame,
    a command the host took as answered that never reached the firmware."""
    with SilSession(speedup=None, key=seeded_key(0)) as sil:
        soak = Soak(sil, SoakConfig(duration_s=1.0))
        soak.host.run_for(0.1)
        soak._digest()
        assert soak.figures.violations == 0
        t_us = sil.plant.time_us
        session, counter = soak.gate.session_id, 1 << 40

        def device_frame(msg: gen.Message, seq: int) -> bytes:
            nonlocal counter
            counter += 1
            return gen.encode_frame(msg, seq, key=sil.key, session_id=session, counter=counter)
        zeros = gen.Telemetry(*([0] * len(gen.Telemetry.FIELDS)))
        bad = [gen.Event(100, 1, gen.EventKind.LOOP_COLLAPSED, 3, 3, 2000),
               gen.Event(100, 2, gen.EventKind.HEARTBEAT_LOST, 3, 3, 900),
               replace(zeros, time_ms=t_us // 1000, rx_duplicates=3)]
        seq = soak._max_seq_seen + 1
        for k, msg in enumerate(bad):
            soak._on_device_frame(t_us, device_frame(msg, seq + k))
        soak._on_delivered_to_device(t_us, b"garbage")
        soak._on_device_frame(t_us, device_frame(gen.Ack(gen.MsgId.ARM, 0, 1), seq + 3))
        # a captured ARM delivered again (counter 1 is long passed) and then answered: the device acted on a replay
        soak._on_delivered_to_device(t_us + 1000, gen.encode_frame(gen.Arm(), 5, key=sil.key, session_id=session,
                                                                     counter=1))
        soak._on_device_frame(t_us + 1000, device_frame(gen.Ack(gen.MsgId.ARM, 5, 1), seq + 4))
        # an unsigned ARM delivered, then a sample that counts neither drop (rx_duplicates as the device said above)
        soak._on_delivered_to_device(t_us + 2000, gen.encode_frame(gen.Arm(), 6))
        later = replace(zeros, time_ms=t_us // 1000 + 5, rx_duplicates=3)
        soak._on_device_frame(t_us + 5000, device_frame(later, seq + 5))
        soak._on_device_frame(t_us + 5000, gen.encode_frame(later, seq + 6))  # unsigned
        soak._answered.append((gen.MsgId.SET_ROPE_SPEED, 4242))  # the host took a verdict the device never gave
        soak._check_final()
        texts = soak.figures.first_violations
        soak.host.close()
        soak.proxy.close()
    assert soak.figures.violations == 9, texts
    assert "LOOP_COLLAPSED" in texts[0] and "HEARTBEAT_LOST after 900 ms" in texts[1]
    assert "rx_duplicates 3, expected 0" in texts[2] and "wrong-direction frame was ACKed" in texts[3]
    assert "verdict" in texts[4] and "for no delivered frame" in texts[4]
    assert "rx_auth_failed 0, expected 1" in texts[5] and "rx_replayed 0, expected 1" in texts[6]
    assert "TELEMETRY unsigned or wrongly signed" in texts[7] and "never reached the firmware" in texts[8]


def test_soak_with_long_delayed_duplicates_executes_nothing_twice(native_build_dir: Path) -> None:
    """Network copies delayed 1.5 s, behind far more than the duplicate cache's 16 newer commands: on the signed
    link their counters are long passed, so each is dropped as a replay and nothing executes twice."""
    link = ImpairmentConfig(to_device=LinkImpairment(duplicate_prob=0.3, reorder_prob=0.15, reorder_delay_ms=1500.0))
    f = run_soak(SoakConfig(duration_s=10.0, seed=3, command_gap_s=(0.02, 0.05), blackout_s=0.0,
                            invalid_fraction=0.0, link=link))
    assert f.violations == 0, "\n".join(f.first_violations)
    assert f.proxy["to_device"]["reordered"] > 50 and f.replays_dropped >= f.proxy["to_device"]["reordered"]
    assert f.commands_executed > 150


def step_down_to_the_guard(*, ramp_down_mps2: float, from_mmps: int) -> tuple[float, list[gen.Event]]:
    """Fly at from_mmps, then command the guard speed (2990 mm/s): lowest plant speed while AIRBORNE, events."""
    with SilSession(speedup=None, trace_every=1, key=seeded_key(0)) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        assert isinstance(host.command(gen.ParamSet(gen.PARAMS_BY_NAME["ramp_down_mps2"].id, ramp_down_mps2)), gen.Ack)
        host.arm_and_spin(from_mmps, settle_s=1.5)
        t0_s = sil.time_s
        assert isinstance(host.command(gen.SetRopeSpeed(GUARD_MMPS)), gen.Ack)
        host.run_for(1.0)
        assert all(t.state == gen.State.AIRBORNE for t in host.received.telemetry if t.time_ms >= t0_s * 1000)
        host.close()
        return (min(s.rope_speed_mps for s in sil.trace if s.time_s >= t0_s),
                [e for e in host.received.events if e.time_ms >= t0_s * 1000])


def test_a_step_down_to_the_guard_keeps_the_rope_over_the_guard(native_build_dir: Path) -> None:
    lowest_mps, _ = step_down_to_the_guard(ramp_down_mps2=10.0, from_mmps=6000)
    assert lowest_mps >= GUARD_MMPS / 1000 - 0.02


def test_a_fast_step_down_to_the_guard_never_drops_the_loop(native_build_dir: Path) -> None:
    lowest_mps, events = step_down_to_the_guard(ramp_down_mps2=200.0, from_mmps=8000)
    assert lowest_mps >= GUARD_MMPS / 1000 - 0.02  # not only over ToV: over the guard
