"""`wrangler sil --scenario NAME --shape-table FILE`: an identified table drives the SIL's rope chain unchanged."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler_sim.identify import identify_manifest, write_identification


def _run(*argv) -> tuple[ExitStatus, str, str]:
    out, err = io.StringIO(), io.StringIO()
    status = main([str(a) for a in argv], Environment(out, err, {}))
    return status, out.getvalue(), err.getvalue()


@pytest.mark.slow
def test_identified_table_runs_a_scenario(photo_set, tmp_path: Path, native_build_dir: Path) -> None:
    table = write_identification(identify_manifest(photo_set.manifest, workers=2), tmp_path / "identified.json")
    status, out, err = _run("--json", "sil", "--scenario", "golf_ball", "--links", "10", "--seed", "1",
                            "--shape-table", table)
    assert status == ExitStatus.OK, err
    result = json.loads(out.strip().splitlines()[-1])
    assert result["shape_table"].startswith("wrangler identify: 7 photos")
    assert result["diverged"] is None and result["verdict"] in ("secured", "slipped")


def test_shape_table_errors_are_usage_errors_naming_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"schema": "robowrangler.shape_table/1", "phi_deg": [0]}')
    status, _, err = _run("sil", "--scenario", "golf_ball", "--shape-table", bad)
    assert status == ExitStatus.USAGE and "bad.json" in err and "missing field" in err
    status, _, err = _run("sil", "--scenario", "golf_ball", "--shape-table", tmp_path / "absent.json")
    assert status == ExitStatus.USAGE and "absent.json" in err
    status, _, err = _run("sil", "--shape-table", bad)
    assert status == ExitStatus.USAGE and "--shape-table needs --scenario" in err
