"""A rope break under load, recorded from a live link to the SIL device (real firmware over UDP, real time): the
recording holds the LOAD_LOST event with the drop it saw, the fault, the landing, and the telemetry that shows
the fault bit - what an operator reads afterwards with `wrangler inspect`."""

from __future__ import annotations

from pathlib import Path

from robowrangler.client import Client
from robowrangler.protocol.generated import State
from robowrangler.recorder import LinkRecorder, RecordingTransport, RecordingWriter, read_recording
from robowrangler.transport import open_transport
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.plant_faults import RopeBreak

TEST_KEY = bytes(range(16))  # the suite's link key (conftest.py provisions the live SIL with it)


def test_a_rope_break_under_load_is_recorded_as_a_load_lost_event(live_sil: SilSession, tmp_path: Path) -> None:
    path = tmp_path / "rope_break.mcap"
    with RecordingWriter(path, source="sil", seed=0, device_url=live_sil.cmd_url) as writer:
        recorder = LinkRecorder(writer)
        transport = RecordingTransport(open_transport(live_sil.cmd_url), recorder)
        with Client(live_sil.cmd_url, transport=transport, key=TEST_KEY) as rw:
            rw.arm(timeout_s=2.0)
            rw.spin(5.0)
            rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
            live_sil.set_rope_load(5.0, at_s=live_sil.time_s + 1.0)  # settled, then the loop drags on an object
            break_s = live_sil.time_s + 2.0
            live_sil.at(break_s, lambda: RopeBreak(start_s=break_s).install(live_sil))
            rw.wait_for_state(State.SPINDOWN, timeout_s=5.0)
            rw.wait_for_state(State.ARMED, timeout_s=3.0)
        recorder.finish()

    rec = read_recording(path)
    assert not rec.truncated
    lost = [e for e in rec.events if e["event"] == "LOAD_LOST"]
    assert len(lost) == 1 and lost[0]["state_from"] == "AIRBORNE" and 1000 < lost[0]["arg"] < 6000  # drop, mN
    assert 0.0 < lost[0]["time_s"] - break_s < 0.7  # device time = plant time in SIL
    raised = [e for e in rec.events if e["event"] == "FAULT_RAISED"]
    assert [e["arg"] for e in raised] == [0x20] and raised[0]["time_s"] == lost[0]["time_s"]  # Fault.LOAD_LOST
    landing = [(e["state_from"], e["state_to"], e["arg"]) for e in rec.events if e["event"] == "STATE_CHANGED"
               and e["time_s"] >= lost[0]["time_s"]]
    assert landing[:2] == [("AIRBORNE", "SPINDOWN", 8), ("SPINDOWN", "ARMED", 1)]  # cause LOAD_LOST, then stopped
    tele = rec.telemetry
    after = [i for i, t in enumerate(tele["time_s"].tolist()) if t > lost[0]["time_s"] + 0.1]
    assert after and all("LOAD_LOST" in list(tele["fault_bits"][i]) for i in after)
