"""`wrangler identify` through the real CLI entry (main(argv, env)): outputs, exit statuses, no partial table."""

from __future__ import annotations

import io
import json

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler_sim.identify.deviation import deviation_m
from robowrangler_sim.shape_table import ShapeTable


def wrangler(*argv):
    env = Environment(stdout=io.StringIO(), stderr=io.StringIO(), environ={})
    status = main([str(a) for a in argv], env)
    return status, env.stdout.getvalue(), env.stderr.getvalue()


def test_manifest_to_table_and_figures(photo_set, tmp_path, manifest_copy):
    manifest = manifest_copy(photo_set, tmp_path / "in", keep=(-30.0, -10.0, 10.0))
    out = tmp_path / "my_table.json"
    status, stdout, stderr = wrangler("--json", "identify", manifest, "--out", out, "--figures", tmp_path / "fig")
    assert status == ExitStatus.OK, stderr
    result = json.loads(stdout)
    assert result["ok"] and result["phi_deg"] == [-30.0, -10.0, 10.0] and result["n_points"] == 41
    table = ShapeTable.load(out)
    for phi in (-30.0, -10.0, 10.0):
        assert deviation_m(photo_set.truth[(5.0, phi)], table.contour(phi))[0] < 0.01 * photo_set.loop_length_m
    assert len(list((tmp_path / "fig").glob("*_identified.png"))) == 3
    assert stderr.count("loop_phi") == 3  # a line per photo


def test_images_named_with_phi_and_speed_and_geometry_on_the_command_line(photo_set, tmp_path):
    data = json.loads(photo_set.manifest.read_text())
    files = [photo_set.folder / p["file"] for p in data["photos"] if p["phi_deg"] in (-20.0, 0.0)]
    u, v = data["exit_px"]
    out = tmp_path / "t.json"
    status, stdout, stderr = wrangler("identify", *files, "--out", out, "--marker-side-m",
                                      data["calibration"]["marker"]["side_m"], "--exit-px", f"{u},{v}",
                                      "--placement", "equal", "--points", "30")
    assert status == ExitStatus.OK, stderr
    assert "wrote" in stdout and ShapeTable.load(out).contours_m.shape == (1, 2, 30, 2)


def test_bad_photo_exits_1_naming_it_and_writes_nothing(photo_set, tmp_path, manifest_copy):
    manifest = manifest_copy(photo_set, tmp_path, keep=(-30.0, -20.0))
    data = json.loads(manifest.read_text())
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"\x89PNG but nothing else")
    data["photos"][1]["file"] = str(broken)
    manifest.write_text(json.dumps(data))
    out = tmp_path / "table.json"
    status, stdout, stderr = wrangler("identify", manifest, "--out", out)
    assert status == ExitStatus.ERROR
    assert stderr.count("\n") == 1 and str(broken) in stderr and "not an image" in stderr
    assert not out.exists() and not list(tmp_path.glob(".table.json*"))


def test_an_existing_table_is_left_whole_when_identification_fails(photo_set, tmp_path):
    out = tmp_path / "table.json"
    out.write_text("previous table\n")
    data = json.loads(photo_set.manifest.read_text())
    u, v = data["exit_px"]
    files = [photo_set.folder / "loop_phi-30.0_v5.0.png", photo_set.folder / "loop_phi-20.0_v5.0.png"]
    status, _, stderr = wrangler("identify", *files, "--out", out, "--marker-side-m", "0.15",
                                 "--exit-px", f"{u + 300},{v}")   # no rope there
    assert status == ExitStatus.ERROR and "no rope loop touches the exit point" in stderr
    assert out.read_text() == "previous table\n"


def test_usage_errors_exit_2(photo_set, tmp_path):
    png = photo_set.folder / "loop_phi-30.0_v5.0.png"
    status, _, stderr = wrangler("identify", png, "--out", tmp_path / "t.json")
    assert status == ExitStatus.USAGE and "no calibration" in stderr
    status, _, stderr = wrangler("identify", png, "--out", tmp_path / "t.json", "--marker-side-m", "0.15",
                                 "--exit-px", "12")
    assert status == ExitStatus.USAGE and "expected U,V" in stderr
    status, _, stderr = wrangler("identify", photo_set.folder / "noname.png", "--out", tmp_path / "t.json",
                                 "--marker-side-m", "0.15")
    assert status == ExitStatus.ERROR and "noname.png: phi missing" in stderr
