"""The simulator as a mechanism: material transport, rope-length bookkeeping, nip slip, module motion,
contact, determinism, typed errors."""

import numpy as np
import pytest

from robowrangler_sim.string_shooter import (AirParams, Capsule, Cylinder, HalfSpace, ModuleGeometry, ModuleMotion, NipParams,
                                             RopeParams, ShooterParams, Sphere, StringShooter,
                                             StringShooterParamError)
from robowrangler_sim.string_shooter.contact import Box, signed_distance_m


def _sim(**kw):
    kw.setdefault("loop_length_m", 1.0)
    return StringShooter(ShooterParams(), **kw)


def test_same_inputs_give_identical_runs():
    runs = []
    for _ in range(2):
        sim = _sim(motion=ModuleMotion(wheel_speed_mps=4.0, phi_rad=lambda t: 0.3 * np.sin(2 * t)))
        rec = sim.run(1.0, frame_interval_s=0.1)
        runs.append(np.concatenate([f.points_m.ravel() for f in rec.frames]))
    assert np.array_equal(runs[0], runs[1])


def test_material_travels_round_the_loop_at_the_rope_speed():
    sim = _sim(motion=ModuleMotion(wheel_speed_mps=5.0))
    sim.step_for(1.0)
    labels0 = sim.frame().labels_m
    sim.step_for(0.2)
    labels1 = sim.frame().labels_m
    # newest material first, each label paid out earlier than the one before it
    assert np.all(np.diff(labels1) < 0)
    # one metre of rope left the eyelet in 0.2 s at 5 m/s
    assert labels1[0] - labels0[0] == pytest.approx(1.0, abs=0.03)
    # material that was in the air has gone back in: the oldest label now is newer than 1 s ago's
    assert labels1[-1] > labels0[-1] + 0.9


def test_rope_length_is_conserved_and_guide_travel_reels_it_in():
    travel = lambda t: np.clip(0.05 * t, 0.0, 0.1)  # 10 cm of guide travel in 2 s
    sim = _sim(loop_length_m=1.5, motion=ModuleMotion(wheel_speed_mps=4.0, guide_travel_m=travel))
    sim.step_for(0.5)
    assert sim.loop_length_m() == pytest.approx(1.5 - 2 * 0.025, abs=2e-3)
    sim.step_for(2.5)
    assert sim.loop_length_m() == pytest.approx(1.5 - 2 * 0.1, abs=2e-3)


def test_the_nip_imposes_the_wheel_speed_and_slips_past_its_friction_limit():
    step = lambda t: np.where(t > 0.1, 6.0, 3.0)
    grip = _sim(motion=ModuleMotion(wheel_speed_mps=step))
    slip = StringShooter(ShooterParams(nip=NipParams(max_traction_n=2e-4)), loop_length_m=1.0,
                         motion=ModuleMotion(wheel_speed_mps=step))
    for sim in (grip, slip):
        sim.step_for(0.15)
    assert grip.rope_speed_mps == pytest.approx(6.0, abs=0.05)
    assert slip.rope_speed_mps < 5.0  # 0.2 mN cannot accelerate the loop by 3 m/s in 50 ms
    assert abs(slip.frame().traction_n) == pytest.approx(2e-4, rel=1e-6)


def test_module_yaw_and_translation_move_the_loop_with_the_module():
    yawed = _sim(motion=ModuleMotion(wheel_speed_mps=5.0, yaw_rad=np.pi / 2, base_position_m=(1.0, 2.0, 1.5)))
    yawed.step_for(1.0)
    pts = yawed.frame().points_m
    assert np.allclose(pts[:, 0], 1.0, atol=1e-6)  # the loop lies in the plane x = 1 (launch along +y)
    assert pts[:, 1].max() > 2.0 + 0.3
    assert pts[0] == pytest.approx([1.0, 2.0 + ModuleGeometry().guide_base_m, 1.5 + ModuleGeometry().exit_offset_m])


def test_a_loop_hanging_onto_the_ground_rests_on_it():
    ground = HalfSpace(point_m=(0.0, 0.0, -0.3))
    sim = _sim(motion=ModuleMotion(wheel_speed_mps=0.5), obstacles=[ground])  # starts as a standing circle
    sim.step_for(1.5)
    z = sim.frame().points_m[:, 2]
    assert z.min() > -0.3 - 1e-3  # no deeper than 1 mm into the ground
    assert z.min() < -0.3 + 0.01  # and lying on it


def test_a_loop_falling_onto_a_sphere_drapes_over_it():
    ball = Sphere(center_m=(0.1, 0.0, -0.3), radius_m=0.08)
    sim = _sim(motion=ModuleMotion(wheel_speed_mps=0.5), obstacles=[ball])
    sim.step_for(1.0)
    d = signed_distance_m(ball, sim.frame().points_m)
    assert d.min() > -1e-3  # no deeper than 1 mm into the ball
    assert d.min() < 0.005  # and touching it


def test_an_obstacle_inside_the_initial_loop_is_refused():
    with pytest.raises(StringShooterParamError, match="obstacles"):
        _sim(obstacles=[HalfSpace(point_m=(0.0, 0.0, -0.3))], initial_shape="hanging")


@pytest.mark.parametrize("obstacle, point, expected", [
    (Sphere(center_m=(0, 0, 0), radius_m=1.0), (2.0, 0, 0), 1.0),
    (Cylinder(end_a_m=(0, 0, 0), end_b_m=(1, 0, 0), radius_m=0.1), (0.5, 0, 0.3), 0.2),
    (Cylinder(end_a_m=(0, 0, 0), end_b_m=(1, 0, 0), radius_m=0.1), (1.5, 0, 0), 0.5),  # flat end
    (Cylinder(end_a_m=(0, 0, 0), end_b_m=(1, 0, 0), radius_m=0.1), (1.3, 0, 0.5), 0.5),  # beyond the rim: 0.3, 0.4
    (Capsule(end_a_m=(0, 0, 0), end_b_m=(1, 0, 0), radius_m=0.1), (1.5, 0, 0), 0.4),  # round end
    (Box(center_m=(0, 0, 0), half_extents_m=(1, 2, 3)), (0, 0, 2.5), -0.5),
    (Box(center_m=(0, 0, 0), half_extents_m=(1, 2, 3)), (1.5, 0, 0), 0.5),
    (Box(center_m=(0, 0, 0), half_extents_m=(1, 2, 3), rotation=((0, -1, 0), (1, 0, 0), (0, 0, 1))), (1.5, 0, 0), -0.5),
    (HalfSpace(point_m=(0, 0, 1)), (5, 5, 0.5), -0.5),
])
def test_obstacle_signed_distances(obstacle, point, expected):
    assert signed_distance_m(obstacle, np.array([point]))[0] == pytest.approx(expected)


def test_tap_gives_the_rope_the_impulse_asked_for():
    sim = _sim(motion=ModuleMotion(wheel_speed_mps=5.0))
    sim.step_for(0.5)
    n = sim.n_nodes
    before = sim.vel[:n].copy()
    label = float(np.median(sim.label[:n]))
    sim.tap(label_m=label, impulse_n_s=1e-5, direction=(0, 1, 0), width_m=0.1)
    dp = (sim.vel[:n] - before)[:, 1].sum() * sim.params.rope.linear_density_kg_per_m * sim.params.numerics.segment_length_m
    assert dp == pytest.approx(1e-5, rel=0.05)


@pytest.mark.parametrize("make, name", [
    (lambda: StringShooter(loop_length_m=0.0), "loop_length_m"),
    (lambda: StringShooter(initial_shape="square"), "initial_shape"),
    (lambda: StringShooter(motion=ModuleMotion(guide_travel_m=0.5)), "guide_travel_m"),
    (lambda: StringShooter(obstacles=["wall"]), "obstacles[0]"),
    (lambda: Sphere(center_m=(0, 0), radius_m=1.0).row(), "center_m"),
    (lambda: StringShooter(loop_length_m=1.0).run(1.0, frame_interval_s=0.0), "frame_interval_s"),
])
def test_bad_input_raises_a_typed_error_naming_the_argument(make, name):
    with pytest.raises(StringShooterParamError, match=name.replace("[", r"\[").replace("]", r"\]")):
        make()


def test_moving_module_in_still_air_equals_still_module_in_wind():
    """Galilean check: translating the module at U through still air gives the same loop, relative to the
    module, as a module standing in a wind of -U."""
    u = np.array([1.5, 0.0, 0.3])
    moving = StringShooter(ShooterParams(), loop_length_m=1.0,
                           motion=ModuleMotion(wheel_speed_mps=5.0, base_position_m=lambda t: np.outer(t, u)))
    windy = StringShooter(ShooterParams().with_(air=AirParams(wind_mps=tuple(-u))), loop_length_m=1.0,
                          motion=ModuleMotion(wheel_speed_mps=5.0))
    for sim in (moving, windy):
        sim.step_for(1.5)
    a, b = moving.frame().points_m - moving.time_s * u, windy.frame().points_m
    assert a.shape == b.shape
    assert np.abs(a - b).max() < 1e-6


def test_a_yawing_module_leaves_the_loop_trailing_behind():
    yaw_rate = 1.0  # rad/s, counter-clockwise seen from above
    sim = _sim(motion=ModuleMotion(wheel_speed_mps=5.0, yaw_rad=lambda t: yaw_rate * t))
    sim.step_for(2.0)
    f = sim.frame()
    lateral = np.array([-np.sin(2.0), np.cos(2.0), 0.0])  # module's left, at t = 2 s
    tip = f.points_m[np.argmax(np.linalg.norm(f.points_m - f.points_m[0], axis=1))]
    assert (tip - f.points_m[0]) @ lateral < -0.01  # the tip lags: it sits to the module's right


def _bend_opening_time_s(bending_n_m2: float, *, width_m: float = 0.15, duration_s: float = 0.4) -> float:
    """A loop folded tight (two strands 4 cm apart) in weightless vacuum, at rest: only bending moves it.
    Time for its width to reach width_m (linear between 2 ms frames); inf if it never does."""
    params = ShooterParams(rope=RopeParams(bending_stiffness_n_m2=bending_n_m2, bending_damping_s=0.0),
                           air=AirParams(density_kg_per_m3=0.0), gravity_mps2=0.0)
    sim = StringShooter(params, loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=0.0), initial_shape="hanging",
                        initial_rope_speed_mps=0.0)
    rec = sim.run(duration_s, frame_interval_s=0.002)
    w = np.array([np.ptp(f.loop_plane_xz_m()[:, 0]) for f in rec.frames])
    if not np.any(w >= width_m):
        return float("inf")
    i = int(np.argmax(w >= width_m))
    t = rec.time_s
    return float(t[i - 1] + (width_m - w[i - 1]) / (w[i] - w[i - 1]) * (t[i] - t[i - 1]))


def test_bending_stiffness_unfolds_a_tight_fold_on_the_elastic_time_scale():
    # with nothing but bending (B) and inertia (lambda), the only time scale is l^2 sqrt(lambda / B):
    # four times stiffer unfolds twice as fast; without stiffness the fold stays (it only settles onto its
    # 2.5 cm segments: 4 -> 6.5 cm in 0.4 s)
    t_soft = _bend_opening_time_s(5e-7)
    t_stiff = _bend_opening_time_s(2e-6)
    assert 0.05 < t_soft < 0.4
    assert t_soft / t_stiff == pytest.approx(2.0, rel=0.05)
    assert _bend_opening_time_s(0.0, width_m=0.1, duration_s=0.4) == float("inf")


@pytest.mark.parametrize("normal_drag_coeff", [1.2, 2.4])
def test_a_slack_rope_falls_broadside_at_the_normal_drag_terminal_speed(normal_drag_coeff):
    # a string twice as long as the 1 m span of the rig, at rest, dropped: its middle falls broadside, so only
    # the normal (pressure) drag 0.5 rho C_n d v^2 per metre acts: v(t) = v_t tanh(g t / v_t),
    # v_t = sqrt(2 lambda g / (rho C_n d)) (1.23 m/s at C_n 1.2), until the slack is used up
    rope = RopeParams(bending_stiffness_n_m2=0.0, compression_stiffness_ratio=0.0, normal_drag_coeff=normal_drag_coeff)
    params = ShooterParams(rope=rope, geometry=ModuleGeometry(span_m=1.0, exit_offset_m=0.0, return_offset_m=0.0))
    sim = StringShooter(params, loop_length_m=2.0, initial_shape="straight", motion=ModuleMotion(wheel_speed_mps=0.0),
                        initial_rope_speed_mps=0.0)
    v_t = np.sqrt(2 * rope.linear_density_kg_per_m * params.gravity_mps2
                  / (params.air.density_kg_per_m3 * normal_drag_coeff * rope.diameter_m))
    for t_s in (0.1, 0.3):
        sim.step_for(t_s - sim.time_s)
        mid = sim.n_nodes // 2
        expected = v_t * np.tanh(params.gravity_mps2 * sim.time_s / v_t)
        assert -sim.vel[mid, 2] == pytest.approx(expected, rel=0.01)
