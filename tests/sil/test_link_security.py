"""Authenticated link over real UDP: only frames signed with the provisioned key, for the current session,
with a fresh counter, move the device; everything else is dropped and counted, and nothing is answered."""

from __future__ import annotations

from pathlib import Path

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost


def test_unsigned_and_forged_commands_are_dropped_and_counted(host: ScriptedHost) -> None:
    before = host.last_telemetry
    acks = len(host.received.acks) + len(host.received.nacks)
    host.send(gen.Arm(), signed=False)                                       # no signature
    host.send_raw(gen.encode_frame(gen.Arm(), 77, key=bytes(16), session_id=host.session_id,
                                   counter=host.counter + 1000))            # wrong key
    host.run_for(0.1)
    t = host.last_telemetry
    assert t.state == gen.State.DISARMED
    assert t.rx_auth_failed == before.rx_auth_failed + 2
    assert len(host.received.acks) + len(host.received.nacks) == acks      # no answer to an unauthenticated sender


def test_a_captured_frame_replayed_is_dropped(host: ScriptedHost) -> None:
    frame = host.frame(gen.Arm(), 900)
    host.send_raw(frame)
    assert host.run_until(lambda h: h.last_telemetry.state == gen.State.ARMED, timeout_s=0.1)
    assert isinstance(host.command(gen.Disarm()), gen.Ack)
    before = host.last_telemetry
    host.send_raw(frame)  # the recorded ARM, sent again by someone on the network
    host.run_for(0.1)
    t = host.last_telemetry
    assert t.state == gen.State.DISARMED and t.rx_replayed == before.rx_replayed + 1


def test_a_retransmission_is_re_signed_and_answered_from_the_cache(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=0.5)
    host.send(gen.SetRopeSpeed(7000), seq=321)
    host.run_for(0.01)
    host.send(gen.SetRopeSpeed(6000))
    host.send(gen.SetRopeSpeed(7000), seq=321)  # the same command, its ACK lost: new counter, same seq/payload
    host.run_for(0.2)
    t = host.last_telemetry
    assert len([a for a in host.received.acks if a.cmd_seq == 321]) == 2
    assert t.rope_speed_target_mmps == 6000 and t.rx_duplicates == 1 and t.rx_replayed == 0


def test_frames_of_an_earlier_boot_never_count_again(native_build_dir: Path, tmp_path: Path) -> None:
    key, flash = bytes(range(16)), tmp_path / "flash.bin"
    with SilSession(speedup=None, key=key, state_file=flash) as first:
        h1 = ScriptedHost(first)
        h1.run_for(0.6)
        captured = h1.frame(gen.Arm(), 5)
        h1.send_raw(captured)
        assert h1.run_until(lambda h: h.last_telemetry.state == gen.State.ARMED, timeout_s=0.1)
        old_session = h1.session_id
        h1.close()
    with SilSession(speedup=None, key=key, state_file=flash, provision=False) as second:  # reboot: same flash
        h2 = ScriptedHost(second)
        assert h2.session_id == old_session + 1
        h2.run_for(0.6)
        h2.send_raw(captured)  # valid signature, earlier session
        h2.run_for(0.1)
        t = h2.last_telemetry
        assert t.state == gen.State.DISARMED and t.rx_replayed == 1
        assert isinstance(h2.command(gen.Arm()), gen.Ack)  # the key survived the reboot
        h2.close()


def test_an_unprovisioned_device_never_moves(native_build_dir: Path) -> None:
    with SilSession(speedup=None, provision=False) as sil:
        host = ScriptedHost(sil, key=bytes(range(16)))
        assert host.received.session_infos[-1].key_set == 0
        host.run_for(0.6)
        host.send(gen.Arm())
        host.send(gen.SetRopeSpeed(5000))
        host.run_for(0.5)
        assert sil.plant.rope_speed_mps == 0.0 and sil.last_esc_pulse_us == 1000
        assert not host.received.acks and not host.received.telemetry  # nobody is a peer
        host.close()


def test_device_frames_are_signed_and_a_wrong_key_host_sees_nothing_valid(host: ScriptedHost) -> None:
    assert host.received.telemetry and host.received.auth_failed == 0
    intruder = ScriptedHost(host.sil, key=bytes(16), handshake=False)
    intruder.send(gen.Hello(1), signed=False)
    intruder.run_for(0.05)
    assert intruder.received.auth_failed >= 1 and not intruder.received.session_infos  # tag does not verify
    intruder.close()
