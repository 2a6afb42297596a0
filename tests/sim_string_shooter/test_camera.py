"""Synthetic camera images: geometry of the projection, the rope where it should be, determinism."""

import cv2
import numpy as np
import pytest

from robowrangler_sim.string_shooter import ModuleMotion, ShooterParams, StringShooter, StringShooterParamError
from robowrangler_sim.string_shooter.camera import ImageStyle, PinholeCamera, render_loop, side_camera


@pytest.fixture(scope="module")
def loop_frames():
    sim = StringShooter(ShooterParams(), loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=5.0))
    sim.step_for(1.5)
    frames = []
    for _ in range(3):
        sim.step_for(0.002)
        frames.append(sim.frame())
    return frames


def test_pinhole_projection():
    cam = PinholeCamera(width_px=101, height_px=81, focal_px=100.0, position_m=(0, -2, 0), look_at_m=(0, 0, 0))
    uv, depth = cam.project(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    assert uv[0] == pytest.approx([50.0, 40.0])
    assert uv[1] == pytest.approx([100.0, 40.0])  # 1 m to the right at 2 m: f / 2 pixels right
    assert uv[2] == pytest.approx([50.0, -10.0])  # 1 m up: f / 2 pixels up (v points down)
    assert depth == pytest.approx([2.0, 2.0, 2.0])


def test_the_rope_is_drawn_where_it_projects(loop_frames):
    f = loop_frames[-1]
    cam = side_camera(guide_m=f.points_m[0], e1=f.e1, loop_length_m=1.0)
    out = render_loop([fr.points_m for fr in loop_frames], cam, seed=3)
    assert out.image.shape == (cam.height_px, cam.width_px) and out.image.dtype == np.uint8
    # binarise as the identification pipeline would: the bright rope against the dark background
    _, binary = cv2.threshold(cv2.GaussianBlur(out.image, (3, 3), 0), 100, 255, cv2.THRESH_BINARY)
    ys, xs = np.nonzero(binary)
    u, v = out.contour_px[:, 0], out.contour_px[:, 1]
    assert xs.min() == pytest.approx(u.min(), abs=4) and xs.max() == pytest.approx(u.max(), abs=4)
    assert ys.min() == pytest.approx(v.min(), abs=4) and ys.max() == pytest.approx(v.max(), abs=4)
    # every bright pixel lies near the projected rope (polyline densified to sub-pixel steps)
    t = np.linspace(0, len(u) - 1, 20 * len(u))
    ud, vd = np.interp(t, np.arange(len(u)), u), np.interp(t, np.arange(len(v)), v)
    d = np.min(np.hypot(xs[:, None] - ud[None], ys[:, None] - vd[None]), axis=1)
    assert np.percentile(d, 99) < 2.0


def test_same_seed_same_image_other_seed_other_noise(loop_frames):
    f = loop_frames[-1]
    cam = side_camera(guide_m=f.points_m[0], e1=f.e1, loop_length_m=1.0)
    a = render_loop(f.points_m, cam, seed=5).image
    b = render_loop(f.points_m, cam, seed=5).image
    c = render_loop(f.points_m, cam, seed=6).image
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_a_noiseless_unblurred_render_matches_its_coverage(loop_frames):
    f = loop_frames[-1]
    cam = side_camera(guide_m=f.points_m[0], e1=f.e1, loop_length_m=1.0)
    style = ImageStyle(texture_amplitude=0.0, noise_std=0.0, shot_noise=0.0, optics_blur_px=0.0,
                       background_top=20.0, background_bottom=20.0, rope_ambient=220.0, rope_diffuse=0.0)
    out = render_loop(f.points_m, cam, seed=0, style=style)
    expected = 20.0 + (220.0 - 20.0) * out.coverage
    assert np.abs(out.image.astype(float) - expected).max() <= 0.51


def test_bad_points_raise():
    with pytest.raises(StringShooterParamError, match="points_m"):
        render_loop(np.zeros((5, 2)), PinholeCamera(), seed=0)


def test_filming_a_run_gives_timed_blurred_frames_deterministically():
    from robowrangler_sim.string_shooter.camera import film

    def shots(seed):
        sim = StringShooter(ShooterParams(), loop_length_m=1.0, motion=ModuleMotion(wheel_speed_mps=5.0, phi_rad=0.2))
        sim.step_for(1.0)
        f = sim.frame()
        cam = side_camera(guide_m=f.points_m[0], e1=f.e1, loop_length_m=1.0, width_px=160, height_px=120,
                          focal_px=200.0)
        return list(film(sim, cam, duration_s=0.1, fps_hz=30.0, exposure_s=0.01, sub_frames=3, seed=seed))

    a, b = shots(1), shots(1)
    assert [s.frame_index for s in a] == [0, 1, 2]
    assert np.diff([s.time_s for s in a]) == pytest.approx(1 / 30, abs=2e-4)
    assert all(np.array_equal(x.rendered.image, y.rendered.image) for x, y in zip(a, b))
    assert not np.array_equal(a[0].rendered.image, a[1].rendered.image)  # new noise each frame
    assert a[0].phi_rad == pytest.approx(0.2) and a[0].rope_speed_mps == pytest.approx(5.0, abs=0.01)
    # a 2 mm rope 2.5 m away at f = 200 px covers 0.16 of a pixel's width: sub-pixel coverage, not lost
    assert a[0].rendered.coverage.max() == pytest.approx(200.0 * 0.002 / 2.5, rel=0.15)
