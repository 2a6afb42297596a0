"""A head wind on the string shooter's loop (the truth): beyond about 0.8 m/s against a 5 m/s rope the outgoing branch
goes into compression, buckles and folds, the loop's reach halves and its contour flutters and comes out shorter than
the rope. No steady law of the loop library represents that: the diagnosis refuses it as a loop that folds and
flutters (LoopFlutterError, with the measurements), not as a wrong rope length; a steady shorter loop still is one."""

from __future__ import annotations

import re

import numpy as np

import pytest

from robowrangler.recorder import RecordingWriter, read_recording
from robowrangler_sim.diagnose import ModelMismatchError
from robowrangler_sim.diagnose.loop import LoopFlutterError, diagnose_loop
from robowrangler_sim.diagnose.loop.proof import LoopScript, LoopTruth, generate_loop_recording

SCRIPT = LoopScript(3.0, ((0.0, 5.0),), ((0.0, 0.1),))


@pytest.fixture(scope="module")
def recs(tmp_path_factory):
    d = tmp_path_factory.mktemp("headwind")
    return {"head": generate_loop_recording(d / "head.mcap", truth=LoopTruth("uniform_wind", wind_mps=-1.8),
                                            script=SCRIPT, seed=21),
            "none": generate_loop_recording(d / "none.mcap", truth=LoopTruth(None), script=SCRIPT, seed=22)}


def test_a_head_wind_that_folds_the_loop_is_refused_as_outside_the_steady_laws(recs):
    with pytest.raises(LoopFlutterError) as err:
        diagnose_loop(recs["head"].path)
    msg = str(err.value)
    assert isinstance(err.value, ModelMismatchError)  # the CLI's exit code for a model that does not fit
    assert "another rope length" not in msg, msg
    assert "flutters unevenly" in msg and "nothing is named" in msg and "head wind" in msg
    p90, q25 = (float(x) for x in re.search(r"\(([\d.]+) mm at the 90th percentile of the points, ([\d.]+) mm at their "
                                            r"lower quartile", msg).groups())
    assert p90 >= 2.0 * q25 and p90 > 8.0  # folds: tens of mm on part of the loop, the camera's 2 mm elsewhere
    reach, reach_model = (float(x) for x in re.search(r"reaches ([\d.]+) m where the model's reaches ([\d.]+) m",
                                                      msg).groups())
    assert reach < 0.7 * reach_model  # the loop is blown back: half the still-air reach


def test_a_steady_shorter_loop_is_a_rope_length_mismatch_and_a_steady_loop_does_not_flutter(recs, tmp_path):
    res = diagnose_loop(recs["none"].path)
    assert res.verdict == "none", res.first_line
    assert res.report["flutter"]["flutters"] is False and res.report["flutter"]["unevenness"] < 1.6
    src = read_recording(recs["none"].path)
    short = tmp_path / "short.mcap"
    with RecordingWriter(short, source="simulator", seed=0, time_base="simulation") as w:
        for r in src.records["/loop/observation"]:
            d = dict(r.data)
            w.write("/loop/observation", {**d, "points_m": [[0.85 * x, 0.85 * z] for x, z in d["points_m"]]},
                    log_time_ns=r.log_time_ns)
    with pytest.raises(ModelMismatchError, match="another rope length.*the contour is steady") as err:
        diagnose_loop(short)
    assert not isinstance(err.value, LoopFlutterError)


def test_the_scatter_tells_a_fold_on_part_of_the_loop_from_camera_noise():
    from robowrangler_sim.diagnose.loop.flutter import contour_scatter
    from robowrangler_sim.diagnose.loop.replay import outward_normals

    rng = np.random.default_rng(3)
    s = np.linspace(0.0, 2.0 * np.pi, 40)
    loop = np.stack([0.4 * (1.0 - np.cos(s)), 0.15 * np.sin(-s)], axis=-1)  # exit at the origin, out along +x
    frames = np.repeat(loop[None], 90, axis=0)
    normals = outward_normals(frames)
    camera = frames + rng.normal(0.0, 0.002, frames.shape)  # the camera's 2 mm on every point
    steady = contour_scatter(camera, normals, np.zeros(90, dtype=int))
    assert not steady.flutters and steady.unevenness < 1.6
    assert 0.0015 < steady.lower_quartile_m < 0.0025
    folded = camera.copy()  # a stretch of the outgoing branch folding: 15 mm along its normals, frame to frame
    folded[:, 10:20] += rng.normal(0.0, 0.015, (90, 10, 1)) * normals[:, 10:20]
    fold = contour_scatter(folded, normals, np.zeros(90, dtype=int))
    assert fold.flutters and fold.p90_m > 0.01 and 0.2 < fold.worst_fraction < 0.55
    assert fold.report()["flutters"] is True and fold.report()["threshold"] == 2.0


def test_a_named_law_on_a_fluttering_loop_says_the_fold_is_left_out():
    from types import SimpleNamespace

    from robowrangler_sim.diagnose.loop.api import LoopFinding
    from robowrangler_sim.diagnose.loop.report import loop_first_line

    e = LoopFinding("uniform_wind", {"wind_speed_mps": {"value": -1.6, "unit": "m/s", "ci95": [-1.8, -1.4]}}, "w",
                    "lower_branch", [], 122.0, 68.0, {})

    def line(flutter: dict) -> str:
        return loop_first_line(SimpleNamespace(verdict="missing_physics", effects=[e], noise_mm=7.0, flutter=flutter,
                                               candidates=[{"heldout_rms_mm": 122.0}]))
    folded = line({"flutters": True, "p90_mm": 14.8, "lower_quartile_mm": 4.8})
    assert folded.endswith("the contour flutters unevenly (14.8 against 4.8 mm): the rope folds on part of the loop, "
                           "which the steady laws leave out")
    assert "flutters" not in line({"flutters": False, "p90_mm": 2.3, "lower_quartile_mm": 1.8})
