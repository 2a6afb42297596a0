"""Frame numbering as a host sees it over real UDP: the device numbers the frames of each link itself, as they
leave, so a host's stream has no holes that the network did not make: not when replies overtake a queued
frame being signed (those arrive out of order by a few ms), not while another host talks to the device over
USB serial, not when the outbox drops a frame."""

from __future__ import annotations

from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler.transport_serial import SerialTransport
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.provisioning_jig import Provisioner
from robowrangler_sim.sil.scripted_host import ScriptedHost

KEY = bytes(range(16))


def _seqs(host: ScriptedHost) -> list[int]:
    return [gen.decode_frame(raw).seq for raw in host.received.raw]


def test_wifi_frames_have_no_holes_under_commands_and_usb_serial_traffic(native_build_dir: Path) -> None:
    with SilSession(speedup=None, key=KEY) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.7)  # past the arming hold
        for _ in range(20):  # commands (ACKed at once) interleaved with queued telemetry and events
            assert isinstance(host.command(gen.ParamGet(0)), gen.Ack)  # ACK now, PARAM_VALUE queued
            host.run_for(0.003)
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        # the queued PARAM_VALUEs leave first: with 12 of them waiting the outbox is full and drops the
        # PROVISION_STATUS (counted); how many are left after the loop depends on the schedule's phase
        host.run_for(0.1)
        transport = SerialTransport(sil.serial_path, url=f"serial://{sil.serial_path}")
        try:  # a second host on the USB serial: its frames are numbered on that link
            status = Provisioner(transport, url="serial", pump=host.tick).status()
        finally:
            transport.close()
        assert status.key_set
        host.run_for(0.3)  # the WiFi host's heartbeats make it the telemetry peer again
        assert isinstance(host.command(gen.Disarm()), gen.Ack)
        host.run_for(0.1)
        seqs = _seqs(host)
        assert len(seqs) > 60 and seqs[0] < seqs[-1] < 65536 - 1  # no wrap in this short run
        assert sorted(seqs) == list(range(seqs[0], seqs[-1] + 1)), "no hole, no repeat"
        late = sum(1 for a, b in zip(seqs, seqs[1:]) if b < a)
        assert 0 < late <= 22, "only frames overtaken by a reply arrive late"  # 22 commands sent
        assert host.received.replayed == 0 and host.received.auth_failed == 0
