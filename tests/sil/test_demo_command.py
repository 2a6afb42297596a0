"""`wrangler demo`, the README's main job, on the simulated rope: exit 0, the plot written, the settle times
and the slowest airborne sample reported (the wrangle part runs the mug scenario, tested in tests/sil_chain)."""

from __future__ import annotations

import io
import json
from pathlib import Path

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main


def test_demo_writes_the_plot_and_reports_the_settle_times(native_build_dir: Path, tmp_path: Path) -> None:
    out, err = io.StringIO(), io.StringIO()
    png = tmp_path / "demo.png"
    status = main(["--json", "demo", "--out", str(png), "--speedup", "3", "--no-wrangle"], Environment(out, err, {}))
    assert status == ExitStatus.OK, err.getvalue()
    (result,) = [json.loads(line) for line in out.getvalue().splitlines() if line.strip()]
    assert result["plot"] == str(png) and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert 0.1 < result["settle_4_mps_s"] < 0.6 and 0.05 < result["settle_6_mps_s"] < 0.4
    assert result["min_airborne_speed_mps"] > 2.99  # never under the ToV guard while airborne
    assert result["wrangle"] is None
    assert "arm" in err.getvalue().lower()  # progress on stderr


def test_demo_refuses_a_speedup_out_of_range(tmp_path: Path) -> None:
    out, err = io.StringIO(), io.StringIO()
    status = main(["demo", "--out", str(tmp_path / "x.png"), "--speedup", "50"], Environment(out, err, {}))
    assert status == ExitStatus.USAGE and "speedup" in err.getvalue()
    assert not (tmp_path / "x.png").exists()
