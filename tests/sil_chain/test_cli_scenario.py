"""`wrangler sil --scenario NAME`: in-process CLI runs (main(argv, env)), real SIL and chain."""

from __future__ import annotations

import io
import json
from pathlib import Path

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


def test_scenario_runs_with_progress_and_a_json_verdict(native_build_dir: Path) -> None:
    status, out, err = _run("--json", "sil", "--scenario", "golf_ball", "--links", "10", "--seed", "1")
    assert status == ExitStatus.OK, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["scenario"] == "golf_ball" and result["verdict"] == "slipped" and result["secured"] is False
    assert result["grasp_end"] == "STROKE_END" and result["diverged"] is None
    assert "RETRACT->ARMED (STROKE_END)" in result["firmware_path"]
    assert "GRASP" in err and "pull" in err  # progress on stderr
