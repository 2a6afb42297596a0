"""`wrangler sil --scenario NAME`: in-process CLI runs (main(argv, env)), real SIL and chain."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main


def _run(*argv: str) -> tuple[ExitStatus, str, str]:
    out, err = io.StringIO(), io.StringIO()
    status = main(list(argv), Environment(out, err, {}))
    return status, out.getvalue(), err.getvalue()


def test_unknown_scenario_is_a_usage_error_naming_the_choices() -> None:
    status, out, err = _run("sil", "--scenario", "wok")
    assert status == ExitStatus.USAGE
    assert "expected one of chips_can," in err and "door_handle" in err and "'wok'" in err
    assert out == ""


def test_help_lists_the_scenarios() -> None:
    status, out, _ = _run("sil", "--help")
    assert status == ExitStatus.OK
    assert "[chips_can|tuna_can|" in out and "|door_handle]" in out


def test_render_without_scenario_is_a_usage_error(tmp_path: Path) -> None:
    status, _, err = _run("sil", "--render", str(tmp_path))
    assert status == ExitStatus.USAGE and "--render needs --scenario" in err


# the golf ball's CLI run (progress, JSON verdict, its explanation) is test_live_loop.py's, which serves it to
# Foxglove as well: one scenario run in CI for both


@pytest.mark.slow
def test_scenario_renders_png_frames_and_an_mp4(native_build_dir: Path, tmp_path: Path) -> None:
    # its own process: MuJoCo's GL backend is fixed at the first import (the CLI picks OSMesa for --render)
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    proc = subprocess.run([sys.executable, "-c", "from robowrangler.cli.main import entry_point; entry_point()",
                           "sil", "--scenario", "golf_ball", "--links", "10", "--render", str(tmp_path)],
                          capture_output=True, text=True, env=env, timeout=900)  # a hang guard
    assert proc.returncode == 0, proc.stderr[-2000:]
    pngs = sorted(p.name for p in tmp_path.glob("golf_ball_*.png"))
    assert len(pngs) > 20 and any(name.endswith("_pull.png") for name in pngs)
    assert (tmp_path / "golf_ball.mp4").stat().st_size > 10_000
    assert "slipped" in proc.stdout
    # every frame carries its caption in a white band on top (time, state, rope speed, guide: caption.py); the
    # last one, golf_ball_verdict.png, two lines: the verdict under it
    import cv2

    for name, lines in ((pngs[len(pngs) // 2], 1), ("golf_ball_verdict.png", 2)):
        img = cv2.imread(str(tmp_path / name))
        band = img[:26 * lines]
        assert (band == 255).mean() > 0.8 and (band[-26:] < 100).any(), name
    import numpy as np

    frames = cv2.VideoCapture(str(tmp_path / "golf_ball.mp4"))
    ok, first = frames.read()
    assert ok and first.shape == (360, 640, 3) and np.mean(first[:26] > 200) > 0.8


def test_door_scenario_shows_the_state_path_ending_in_hold(native_build_dir: Path) -> None:
    status, out, err = _run("sil", "--scenario", "door_handle", "--links", "10")
    assert status == ExitStatus.OK, err
    path_line = next(line for line in out.splitlines() if line.startswith("firmware state path:"))
    assert path_line.endswith("RETRACT (SPEED_REACHED) -> HOLD (LOAD_SECURED)"), path_line
    assert "door_handle: held (RETRACT ended: LOAD_SECURED" in out and ", door opened 1" in out


def test_divergence_exits_1_with_the_outcome_on_stdout(native_build_dir: Path, monkeypatch) -> None:
    from robowrangler_sim.chain.errors import ChainDivergenceError
    from robowrangler_sim.chain.plant import ChainPlant

    step = ChainPlant.step

    def diverging_step(self, inputs=None):
        step(self, inputs)
        if self.time_s >= 3.0:
            raise ChainDivergenceError(time_s=self.time_s, reason="nonfinite", detail="injected by the test")

    monkeypatch.setattr(ChainPlant, "step", diverging_step)
    status, out, err = _run("--json", "sil", "--scenario", "mug", "--links", "10")
    assert status == ExitStatus.ERROR
    lines = [json.loads(line) for line in out.strip().splitlines()]
    assert lines[0]["verdict"] == "diverged" and "nonfinite" in lines[0]["diverged"]
    assert "scenario mug: diverged" in err


def test_an_interrupted_scenario_says_where_it_stopped_and_what_it_left(native_build_dir: Path, monkeypatch) -> None:
    """Ctrl-C in the middle of a wrangle: exit 130, one line naming the phase, the simulated time, the firmware's
    states so far and that the SIL firmware was stopped (frames and MP4 with --render: see the slow render test)."""
    from robowrangler_sim.chain.plant import ChainPlant

    step = ChainPlant.step

    def interrupted_step(self, inputs=None):
        step(self, inputs)
        if self.time_s >= 2.0:
            raise KeyboardInterrupt

    monkeypatch.setattr(ChainPlant, "step", interrupted_step)
    status, out, err = _run("sil", "--scenario", "mug", "--links", "10")
    assert status == ExitStatus.CTRL_C and out == ""
    left = next(line for line in err.splitlines() if "interrupted in phase" in line)
    assert left.startswith("wrangler: scenario mug interrupted in phase home at 2.0 simulated s, no verdict")
    assert "firmware states unchanged since boot" in left and "the SIL firmware is stopped" in left
    assert err.splitlines()[-1] == "wrangler: interrupted"
