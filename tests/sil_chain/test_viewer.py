"""`wrangler sil --scenario NAME --viewer`: the live viewer's checks without a display, and its pacing."""

from __future__ import annotations

import io

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler_sim.scenarios import run_scenario
from robowrangler_sim.scenarios.viewer import ScenarioViewer, ViewerUnavailable, viewer_unavailable_reason


def _run(environ: dict, *argv: str) -> tuple[ExitStatus, str, str]:
    out, err = io.StringIO(), io.StringIO()
    status = main(list(argv), Environment(out, err, environ))
    return status, out.getvalue(), err.getvalue()


def test_viewer_without_a_display_exits_1_naming_mujoco_gl_and_display() -> None:
    status, out, err = _run({}, "sil", "--scenario", "mug", "--viewer")
    assert status == ExitStatus.ERROR
    assert "--viewer" in err and "DISPLAY" in err and "MUJOCO_GL" in err and "--render" in err
    assert out == ""
    # a headless GL backend cannot open a window even where a display exists
    status, _, err = _run({"DISPLAY": ":0", "MUJOCO_GL": "osmesa"}, "sil", "--scenario", "mug", "--viewer")
    assert status == ExitStatus.ERROR and "MUJOCO_GL='osmesa'" in err


def test_viewer_needs_a_scenario_and_excludes_render(tmp_path, monkeypatch) -> None:
    for name in ("MUJOCO_GL", "PYOPENGL_PLATFORM"):  # --render picks OSMesa in this process: restored after the test
        monkeypatch.delenv(name, raising=False)
    status, _, err = _run({}, "sil", "--viewer")
    assert status == ExitStatus.USAGE and "--viewer needs --scenario" in err
    status, _, err = _run({"DISPLAY": ":0"}, "sil", "--scenario", "mug", "--viewer", "--render", str(tmp_path))
    assert status == ExitStatus.USAGE and "cannot be combined" in err


def test_run_scenario_refuses_the_viewer_before_starting_anything(monkeypatch) -> None:
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL"):
        monkeypatch.delenv(name, raising=False)
    with pytest.raises(ViewerUnavailable, match="DISPLAY"):
        run_scenario("mug", viewer=True)


def test_reason_per_environment() -> None:
    assert viewer_unavailable_reason({"DISPLAY": ":1"}, platform="linux") is None
    assert viewer_unavailable_reason({"WAYLAND_DISPLAY": "wayland-0", "MUJOCO_GL": "glfw"}, platform="linux") is None
    assert "DISPLAY" in viewer_unavailable_reason({}, platform="linux")
    assert viewer_unavailable_reason({}, platform="darwin") is None  # no X11 variable there
    assert "MUJOCO_GL='egl'" in viewer_unavailable_reason({"MUJOCO_GL": "egl"}, platform="darwin")


class _Window:
    """The window part of mujoco.viewer's passive handle (sync, is_running, close); no GL here."""

    def __init__(self) -> None:
        self.synced = 0
        self.running = True
        self.closed = False

    def sync(self) -> None:
        self.synced += 1

    def is_running(self) -> bool:
        return self.running

    def close(self) -> None:
        self.closed = True


def test_viewer_paces_simulated_time_to_wall_time_and_stops_syncing_once_closed() -> None:
    window = _Window()
    wall = [100.0]
    slept = []

    def sleep(dt_s: float) -> None:
        slept.append(dt_s)
        wall[0] += dt_s

    viewer = ScenarioViewer(object(), object(), speedup=2.0, launch=lambda m, d: window, clock_s=lambda: wall[0],
                            sleep_s=sleep)
    for k in range(5):  # chain steps of 2 ms, computed in no wall time: 10 ms simulated = 5 ms wall at 2x
        viewer.sync(1.0 + 0.002 * k)
    assert window.synced == 5 and sum(slept) == pytest.approx(0.004)
    window.running = False  # the user closed the window: the run goes on unpaced
    viewer.sync(1.01)
    assert window.synced == 5 and len(slept) == 4
    viewer.close()
    assert window.closed and not viewer.open
    with pytest.raises(ValueError, match="speedup: expected a finite factor > 0, got 0"):
        ScenarioViewer(object(), object(), speedup=0, launch=lambda m, d: window)
