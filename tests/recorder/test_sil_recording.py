"""Recording a live link to the SIL device (real firmware over UDP, real time): the file holds what the
client saw, the commands with their verdicts, the events, and every frame the link lost."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from robowrangler.client import Client
from robowrangler.errors import CommandRefused
from robowrangler.protocol.generated import NackReason, State
from robowrangler.recorder import LinkRecorder, RecordingTransport, RecordingWriter, read_recording
from robowrangler.transport import Transport, open_transport
from robowrangler_sim.sil import SilSession

TEST_KEY = bytes(range(16))  # the suite's link key (conftest.py provisions the live SIL with it)


def test_recording_of_a_spin_holds_the_telemetry_the_client_saw(live_sil: SilSession, tmp_path: Path) -> None:
    path = tmp_path / "spin.mcap"
    seen = []
    with RecordingWriter(path, source="sil", seed=0, device_url=live_sil.cmd_url) as writer:
        recorder = LinkRecorder(writer)
        transport = RecordingTransport(open_transport(live_sil.cmd_url), recorder)
        with Client(live_sil.cmd_url, transport=transport, key=TEST_KEY) as rw:
            stop = threading.Event()
            stream = rw.telemetry()

            def collect() -> None:
                for sample in stream:
                    seen.append(sample)
                    if stop.is_set():
                        break

            collector = threading.Thread(target=collect)
            collector.start()
            rw.arm(timeout_s=2.0)
            rw.spin(4.0)
            airborne_s = rw.wait_for_state(State.AIRBORNE, timeout_s=3.0).time_s
            # fly for a second of the device's time (wall time would give fewer samples on a busy machine)
            rw.wait_for(lambda s: s.time_s >= airborne_s + 1.0, timeout_s=30.0)
            with pytest.raises(CommandRefused):
                rw.spin(2.0)  # under the ToV guard: NACK
            rw.spindown()
            rw.wait_for_state(State.ARMED, timeout_s=5.0)
            stop.set()
            collector.join(timeout=5.0)
        recorder.finish()

    rec = read_recording(path)
    assert not rec.truncated and rec.meta["source"] == "sil" and rec.meta["device_url"] == live_sil.cmd_url
    tele = rec.telemetry
    row_of = {t: i for i, t in enumerate(tele["time_s"].tolist())}
    assert len(seen) > 60 and len(tele["time_s"]) >= len(seen)
    for sample in seen:
        i = row_of[sample.time_s]  # every sample the client saw is in the recording ...
        for key, value in sample.to_dict().items():  # ... with the same values, bit for bit
            if key in tele and key != "received_s":
                recorded = tele[key][i]
                assert (list(recorded) if isinstance(recorded, tuple) else recorded) == value, key
    assert max(tele["rope_speed_mps"]) == pytest.approx(4.0, abs=0.3)
    # the device's outbox drops a telemetry frame when replies crowd a tick (its seq is spent): a gap of 1
    assert all(g["missing"] == 1 for g in rec.gaps) and len(rec.gaps) <= 5
    assert not {g["from_seq"] for g in rec.gaps} & set(tele["seq"].tolist())

    commands = [(c["message"], c["verdict"], c["reason"]) for c in rec.commands]
    assert commands == [("ARM", "ACK", None), ("SET_ROPE_SPEED", "ACK", None),
                        ("SET_ROPE_SPEED", "NACK", NackReason.BELOW_TOV_GUARD.name), ("SPINDOWN", "ACK", None)]
    assert [c["fields"] for c in rec.commands[1:3]] == [{"rope_speed_mps": 4.0}, {"rope_speed_mps": 2.0}]
    assert all(0 < c["reply_latency_s"] < 1.0 for c in rec.commands)
    transitions = [(e["state_from"], e["state_to"]) for e in rec.events if e["event"] == "STATE_CHANGED"]
    expected = [("DISARMED", "ARMED"), ("ARMED", "SPINUP"), ("SPINUP", "AIRBORNE"), ("AIRBORNE", "SPINDOWN"),
                ("SPINDOWN", "ARMED")]
    it = iter(transitions)
    assert all(step in it for step in expected), transitions  # in this order


class DroppingTransport(Transport):
    """Drops chosen received datagrams (by arrival index) as a lossy WiFi link would."""

    def __init__(self, inner: Transport, drop: set[int]) -> None:
        self.inner, self.drop, self.url = inner, drop, inner.url
        self.index = 0
        self.dropped_seqs: list[int] = []

    def send(self, frame: bytes) -> None:
        self.inner.send(frame)

    def recv(self, timeout_s: float) -> bytes | None:
        data = self.inner.recv(timeout_s)
        if data is not None:
            self.index += 1
            if self.index - 1 in self.drop:
                self.dropped_seqs.append(int.from_bytes(data[4:6], "little"))
                return None
        return data

    def close(self) -> None:
        self.inner.close()


def test_datagrams_lost_on_the_link_are_recorded_as_gaps(live_sil: SilSession, tmp_path: Path) -> None:
    path = tmp_path / "lossy.mcap"
    drop = set(range(30, 40)) | {80, 81, 82}
    with RecordingWriter(path, source="sil") as writer:
        recorder = LinkRecorder(writer)
        lossy = DroppingTransport(open_transport(live_sil.cmd_url), drop)
        with Client(live_sil.cmd_url, transport=RecordingTransport(lossy, recorder), key=TEST_KEY):
            deadline = time.monotonic() + 5.0
            while lossy.index < 100 and time.monotonic() < deadline:
                time.sleep(0.05)
        recorder.finish()
    rec = read_recording(path)
    assert lossy.dropped_seqs and len(lossy.dropped_seqs) == 13
    gaps = [(g["from_seq"], g["to_seq"], g["missing"]) for g in rec.gaps]
    d = lossy.dropped_seqs
    assert gaps == [(d[0], d[9], 10), (d[10], d[12], 3)]
    g = rec.gaps[0]
    assert g["resume_time_s"] - g["last_time_s"] == pytest.approx(11 * 0.02, abs=0.002)  # 50 Hz telemetry
    assert not set(d) & set(rec.telemetry["seq"].tolist())
