"""Takeoff from first principles: our rope lifts near 2.6 m/s, independently of loop length and launch
angle, and never without air. Coarse loops (<= 1 m) and short settling keep this fast; the full sweeps
(2 m loops, more angles) are in bench/bench_string_shooter.py."""

import numpy as np
import pytest

from robowrangler_sim.string_shooter import ModuleMotion, ShooterParams, StringShooter, takeoff_speed_estimate_mps
from robowrangler_sim.string_shooter.takeoff import find_takeoff_speed, no_air, steady_depth_fraction

SPEEDS = np.arange(1.65, 3.2, 0.15)


@pytest.fixture(scope="module")
def takeoff_by_case():
    out = {}
    for length_m, phi_deg in [(0.4, 0.0), (1.0, 0.0), (1.0, -20.0), (1.0, 20.0)]:
        out[(length_m, phi_deg)] = find_takeoff_speed(
            ShooterParams(), loop_length_m=length_m, phi_rad=np.radians(phi_deg), speeds_mps=SPEEDS, settle_s=3.0
        ).speed_mps
    return out


def test_drag_coefficients_put_the_theoretical_takeoff_at_2_6_mps():
    assert takeoff_speed_estimate_mps(ShooterParams().rope, ShooterParams().air) == pytest.approx(2.6, rel=0.01)


def test_our_rope_lifts_at_2_6_mps_within_15_percent(takeoff_by_case):
    assert takeoff_by_case[(1.0, 0.0)] == pytest.approx(2.6, rel=0.15)


def test_takeoff_speed_does_not_depend_on_loop_length(takeoff_by_case):
    short, long_ = takeoff_by_case[(0.4, 0.0)], takeoff_by_case[(1.0, 0.0)]
    assert abs(short - long_) / long_ < 0.10


def test_takeoff_speed_does_not_depend_on_launch_angle(takeoff_by_case):
    speeds = [takeoff_by_case[(1.0, phi)] for phi in (-20.0, 0.0, 20.0)]
    mean = np.mean(speeds)
    assert max(abs(s - mean) for s in speeds) / mean < 0.10


def test_takeoff_follows_the_drag_balance_when_the_drag_changes():
    """Halving C_f must raise v* by sqrt(2): the lift is axial drag, not an artefact of the model."""
    params = ShooterParams()
    weak = params.with_(rope=params.rope.with_(skin_friction_coeff=params.rope.skin_friction_coeff / 2))
    v = find_takeoff_speed(weak, loop_length_m=1.0, speeds_mps=np.arange(2.2, 4.45, 0.15), baseline_below_mps=3.0,
                           settle_s=3.0).speed_mps
    assert v == pytest.approx(2.6 * np.sqrt(2), rel=0.12)


@pytest.mark.parametrize("speed_mps", [3.0, 8.0])
def test_without_air_the_loop_hangs_at_any_speed(speed_mps):
    """Spun up (2 s ramp) from a hanging loop in vacuum, it stays hanging: no drag, no lift."""
    params = no_air(ShooterParams())
    motion = ModuleMotion(wheel_speed_mps=lambda t: speed_mps * np.clip(t / 2.0, 0.0, 1.0))
    sim = StringShooter(params, loop_length_m=1.0, motion=motion, initial_shape="hanging")
    rec = sim.run(4.0, frame_interval_s=0.05)
    depths = []
    for frame in rec.frames:
        xz = frame.loop_plane_xz_m()
        assert xz[:, 1].max() < 0.05  # nothing rises above the eyelet
        if frame.time_s >= 2.0:
            depths.append(-xz[:, 1].min())
    assert np.mean(depths) / 0.5 > 0.8  # at full speed it hangs nearly its full half-length
    assert rec.frames[-1].rope_speed_mps == pytest.approx(speed_mps, rel=0.01)
    if speed_mps == 8.0:  # the same loop in air flies: the air, not the speed, lifts it
        flying = steady_depth_fraction(ShooterParams(), rope_speed_mps=speed_mps, loop_length_m=1.0, phi_rad=0.0,
                                       settle_s=3.0)
        assert flying < 0.4


def test_loop_collapses_when_the_speed_falls_below_takeoff_and_lifts_again_above_it():
    """Ramp 5 -> 1.8 -> 5 m/s: the loop comes down below v* and goes back up above it (no lasting hysteresis)."""
    def wheel(t):
        return np.interp(t, [0.0, 2.0, 3.0, 6.0, 7.0, 10.0], [5.0, 5.0, 1.8, 1.8, 5.0, 5.0])

    sim = StringShooter(ShooterParams(), loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=wheel))
    rec = sim.run(10.0, frame_interval_s=0.1)
    depth = {round(f.time_s, 1): -f.loop_plane_xz_m()[:, 1].min() / 0.5 for f in rec.frames}
    assert depth[2.0] < 0.5  # flying at 5 m/s
    assert depth[6.0] > 0.85  # hanging after 3 s at 1.8 m/s
    assert depth[10.0] == pytest.approx(depth[2.0], abs=0.03)  # flying again, same shape
