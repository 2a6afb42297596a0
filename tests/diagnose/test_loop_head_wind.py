"""A head wind on the string shooter's loop (the truth): beyond about 0.8 m/s against a 5 m/s rope the outgoing branch
goes into compression, buckles and folds, the loop's reach halves and its contour flutters and comes out shorter than
the rope. No steady law of the loop library represents that: the diagnosis refuses it as a loop that folds and
flutters (LoopFlutterError, with the measurements), not as a wrong rope length; a steady shorter loop still is one."""

from __future__ import annotations

import re

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
