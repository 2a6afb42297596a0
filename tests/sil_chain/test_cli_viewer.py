"""`wrangler sil --scenario NAME --viewer`: MuJoCo's interactive viewer synced with the chain while the firmware runs.

Fast: without a display (or with a headless MUJOCO_GL) the command exits 1 at once, naming MUJOCO_GL and DISPLAY;
the option's usage errors. Slow: a real viewer window on a virtual X display (Xvfb, Debian package xvfb; skipped
where xvfb-run is missing), whose run has the same outcome as the run without a viewer.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main


def _run(*argv: str, environ: dict[str, str] | None = None) -> tuple[ExitStatus, str, str]:
    out, err = io.StringIO(), io.StringIO()
    status = main(list(argv), Environment(out, err, environ or {}))
    return status, out.getvalue(), err.getvalue()


def test_viewer_without_a_display_exits_1_naming_mujoco_gl_and_display() -> None:
    status, out, err = _run("sil", "--scenario", "mug", "--viewer")
    assert status == ExitStatus.ERROR
    assert out == ""
    line, = err.strip().splitlines()  # one line, before anything ran (no progress)
    assert "--viewer" in line and "DISPLAY" in line and "MUJOCO_GL" in line and "--render DIR" in line
    assert "GRASP" not in err


def test_viewer_with_a_headless_gl_backend_names_mujoco_gl_in_the_json_error() -> None:
    status, out, err = _run("--json", "sil", "--scenario", "mug", "--viewer",
                            environ={"DISPLAY": ":0", "MUJOCO_GL": "osmesa"})
    assert status == ExitStatus.ERROR
    result = json.loads(out)
    assert result["exit_code"] == 1 and result["error"] == "SimulatorUnavailable"
    assert "MUJOCO_GL='osmesa'" in result["message"] and "DISPLAY" in result["message"]


def test_viewer_usage_errors() -> None:
    status, _, err = _run("sil", "--viewer")
    assert status == ExitStatus.USAGE and "--viewer needs --scenario" in err
    status, _, err = _run("sil", "--scenario", "mug", "--viewer", "--render", "/tmp/never_written")
    assert status == ExitStatus.USAGE and "--viewer and --render cannot be combined" in err


def test_an_unreachable_display_is_a_clear_error_not_a_dead_process(native_build_dir: Path) -> None:
    # DISPLAY set but no X server behind it: GLFW cannot init. MuJoCo's viewer would end the process from its own
    # thread; the CLI asks GLFW first and exits 1 with the reason.
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "WAYLAND_DISPLAY")}
    env["DISPLAY"] = ":97"
    proc = subprocess.run([sys.executable, "-c", "from robowrangler.cli.main import entry_point; entry_point()",
                           "sil", "--scenario", "golf_ball", "--links", "10", "--viewer"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 1, proc.stderr[-2000:]
    assert "GLFW could not reach the display" in proc.stderr and ":97" in proc.stderr
    assert "GRASP" not in proc.stderr  # nothing ran


@pytest.mark.slow
def test_viewer_on_a_virtual_display_follows_the_run_without_changing_it(native_build_dir: Path,
                                                                         skip_unless_ci) -> None:
    from robowrangler_sim.scenarios import run_scenario

    if shutil.which("xvfb-run") is None:
        skip_unless_ci("needs xvfb-run (Debian package xvfb) for a display")

    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    proc = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x720x24", sys.executable, "-c",
                           "from robowrangler.cli.main import entry_point; entry_point()",
                           "--json", "sil", "--scenario", "golf_ball", "--links", "10", "--viewer", "--speedup", "20"],
                          capture_output=True, text=True, env=env, timeout=280)
    assert proc.returncode == 0, proc.stderr[-2000:]
    viewed = json.loads(proc.stdout.strip().splitlines()[-1])
    # the viewer was updated through the whole run (about 50 per simulated second: one per 5 ms chain step at most)
    assert viewed["viewer_updates"] > 25 * viewed["simulated_s"]
    assert "viewer:" in proc.stderr
    plain = run_scenario("golf_ball", seed=0, n_links=10)
    assert viewed["verdict"] == plain.verdict and viewed["grasp_end"] == plain.grasp_end
    assert viewed["follow_ratio"] == round(plain.follow_ratio, 3)
    assert viewed["touching_fraction"] == round(plain.touching_fraction, 3)


class _Window:
    """Stands in for MuJoCo's viewer handle where no display exists: records what ScenarioViewer asks of it."""

    def __init__(self, close_after_syncs: int | None = None) -> None:
        import contextlib

        import numpy as np

        self.syncs = 0
        self.closed = False
        self.close_after_syncs = close_after_syncs
        self.cam = type("Cam", (), {"lookat": np.zeros(3), "distance": 0.0, "azimuth": 0.0, "elevation": 0.0})()
        self.lock = contextlib.nullcontext

    def sync(self) -> None:
        self.syncs += 1

    def is_running(self) -> bool:
        return self.close_after_syncs is None or self.syncs < self.close_after_syncs

    def close(self) -> None:
        self.closed = True


def test_scenario_viewer_syncs_at_its_rate_and_paces_a_real_chain_to_the_speedup() -> None:
    from robowrangler_sim.chain.default_table import default_or_synthetic_table
    from robowrangler_sim.chain.params import ChainParams
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs
    from robowrangler_sim.scenarios.viewer import ScenarioViewer

    chain = ChainPlant(table=default_or_synthetic_table(), params=ChainParams(n_links=10),
                       initial=PlantInputs(rope_speed_mps=4.0))
    window = _Window()
    wall = [100.0]
    slept: list[float] = []

    def sleep(s: float) -> None:
        slept.append(s)
        wall[0] += s

    with ScenarioViewer(speedup=2.0, sync_hz=50.0, launch=lambda m, d: window, clock_s=lambda: wall[0],
                        sleep_s=sleep) as viewer:
        for _ in range(200):  # 1 s of chain at 5 ms, the viewer called as after each 5 ms of control ticks
            chain.step()
            viewer(chain)
        assert window.cam.distance > 1.0  # the camera frames the loop
    assert window.closed and viewer.synced == window.syncs == 50  # 50 per simulated second
    # paced: 1 simulated s (less the first 20 ms, the pacing origin) at 2x takes 0.49 s of wall time
    assert sum(slept) == pytest.approx(0.49, abs=1e-6)
    closing = _Window(close_after_syncs=3)
    viewer = ScenarioViewer(speedup=None, launch=lambda m, d: closing)
    for _ in range(100):
        chain.step()
        viewer(chain)
    assert viewer.closed_by_user and closing.syncs == 3  # the user closed the window: no more drawing


def test_scenario_viewer_rejects_bad_options() -> None:
    from robowrangler_sim.scenarios.viewer import ScenarioViewer

    with pytest.raises(ValueError, match="speedup: expected a positive factor or None"):
        ScenarioViewer(speedup=0.0)
    with pytest.raises(ValueError, match="sync_hz: expected 1..1000"):
        ScenarioViewer(sync_hz=0.5)
