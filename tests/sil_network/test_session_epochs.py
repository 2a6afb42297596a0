"""Session ids across provisionings (SIL, real sockets): a firmware upload erases the flash, so the boot counter
starts again; the random session epoch of each provisioning keeps the session ids of two provisionings with the
same key apart, and a frame recorded under the earlier one is refused as a replay.

The flash erase is the SIL state file removed between the two provisionings.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from robowrangler.errors import CommandRefused, LinkTimeout
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import State
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost

KEY = bytes(range(0x40, 0x50))
BOOTS = 3


def session_ids_of_one_provisioning(state_file: Path) -> tuple[list[int], bytes]:
    """Provision (fresh flash) with KEY, then reboot BOOTS - 1 times: the session id of each boot, and one
    signed ARM frame the device accepted in the first session (what an eavesdropper could record)."""
    ids: list[int] = []
    recorded = b""
    for boot in range(BOOTS):
        with SilSession(speedup=None, key=KEY, provision=boot == 0, state_file=state_file) as sil:
            host = ScriptedHost(sil)
            ids.append(host.session_id)
            if boot == 0:
                host.run_for(0.6)  # the ESC arming hold
                recorded = host.frame(gen.Arm(), 77)
                host.send_raw(recorded)
                host.run_for(0.05)
                assert host.last_telemetry.state == State.ARMED  # the frame was genuine
            host.close()
    return ids, recorded


def test_two_provisionings_with_the_same_key_have_disjoint_session_ids_and_refuse_old_frames(
        tmp_path: Path, native_build_dir: Path) -> None:
    flash = tmp_path / "flash.bin"
    first, recorded = session_ids_of_one_provisioning(flash)
    assert first == list(range(first[0], first[0] + BOOTS))  # epoch + boot counter: one more per boot
    flash.unlink()  # a firmware upload erases the flash: the boot counter starts again
    second, _ = session_ids_of_one_provisioning(flash)
    assert second == list(range(second[0], second[0] + BOOTS))
    assert not set(first) & set(second)  # P(overlap) = (2 BOOTS - 1) / 2^31 ~ 2e-9

    # the frame recorded under the first provisioning, replayed to the re-provisioned device (same key)
    with SilSession(speedup=None, key=KEY, state_file=flash) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        replayed_before = host.last_telemetry.rx_replayed
        host.send_raw(recorded)
        host.run_for(0.05)
        t = host.last_telemetry
        assert t.rx_replayed == replayed_before + 1 and t.state == State.DISARMED  # dropped, counted, not armed
        assert isinstance(host.command(gen.Arm()), gen.Ack)  # a fresh frame of this session is taken
        host.close()


def test_a_provisioning_commit_starts_a_new_session_at_once(native_build_dir: Path) -> None:
    """Between the boot and the commit the device ran session 1 of its blank flash; frames for that session
    (which every erased device has) never count after the commit."""
    with SilSession(speedup=None, key=KEY) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        assert host.session_id != 1
        stale = gen.encode_frame(gen.Arm(), 5, key=KEY, session_id=1, counter=1)
        host.send_raw(stale)
        host.run_for(0.05)
        assert host.last_telemetry.rx_replayed == 1 and host.last_telemetry.state == State.DISARMED
        host.close()


def test_an_epoch_out_of_range_is_refused_and_changes_nothing(native_build_dir: Path) -> None:
    with SilSession(speedup=None, key=KEY) as sil:
        host = ScriptedHost(sil)  # a host connects after the provisioning (a commit starts a new session range)
        session = host.session_id
        with pytest.raises(CommandRefused) as refused:
            sil.provision(session_epoch=1 << 31)
        assert refused.value.reason == gen.NackReason.OUT_OF_RANGE and refused.value.detail == (1 << 31) - 1
        assert host.hello().session_id == session  # the session stays
        host.run_for(0.6)
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        host.close()


def test_the_stored_epoch_again_is_refused_and_a_captured_frame_stays_a_replay(native_build_dir: Path) -> None:
    with SilSession(speedup=None, key=KEY, provision=False) as sil:
        sil.provision(key=KEY, session_epoch=0x1234)
        host = ScriptedHost(sil)
        assert host.session_id == 0x1234
        host.run_for(0.6)
        captured = host.frame(gen.Arm(), 7)
        host.send_raw(captured)
        assert host.run_until(lambda h: h.last_telemetry.state == State.ARMED, timeout_s=0.1)
        assert isinstance(host.command(gen.Disarm()), gen.Ack)
        with pytest.raises(CommandRefused) as refused:  # would restart session 0x1234 with its counter at 0
            sil.provision(session_epoch=0x1234)
        assert refused.value.reason == gen.NackReason.OUT_OF_RANGE and refused.value.detail == 0x1234
        sent_ms = host.last_telemetry.time_ms
        host.send_raw(captured)
        assert host.run_until(lambda h: h.last_telemetry.time_ms > sent_ms + 30, timeout_s=0.2)
        assert host.last_telemetry.rx_replayed == 1 and host.last_telemetry.state == State.DISARMED
        host.close()


def test_a_connected_host_follows_a_re_provisioning_to_a_lower_session_by_saying_hello(native_build_dir: Path) -> None:
    """A new epoch may put the session below the one a host signs for. The host's HELLO is answered for the new
    session, and that answer (its nonce echoed) is what the host follows (robowrangler.link_session); the
    former tuple rule of the scripted host dropped it as a replay and lost the device for good."""
    with SilSession(speedup=None, key=KEY, provision=False) as sil:
        sil.provision(key=KEY, session_epoch=0x50000)
        host = ScriptedHost(sil)
        host.run_for(0.6)
        assert isinstance(host.command(gen.Arm()), gen.Ack) and isinstance(host.command(gen.Disarm()), gen.Ack)
        sil.provision(session_epoch=0x1000)  # the device runs session 0x1000 at once
        with pytest.raises(LinkTimeout):  # signed for session 0x50000: dropped unanswered
            host.command(gen.Arm())
        assert host.hello().session_id == 0x1000 and host.session_id == 0x1000
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        assert host.run_until(lambda h: h.last_telemetry.state == State.ARMED, timeout_s=0.1)
        host.close()
