"""Bad input over the real UDP link: every frame gets a verdict with a reason, is counted, and moves nothing."""

from __future__ import annotations

import pytest

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.scripted_host import ScriptedHost


def _raw_verdict(host: ScriptedHost, data: bytes) -> gen.Nack:
    before = len(host.received.nacks)
    host.send_raw(data)
    host.run_for(0.005)
    assert len(host.received.nacks) == before + 1, "every refused frame gets exactly one NACK"
    return host.received.nacks[-1]


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"\x01", gen.NackReason.TRUNCATED),
        (b"\x00" * 12, gen.NackReason.BAD_MAGIC),
        (bytes([gen.MAGIC]) + b"\xff" * 2000, gen.NackReason.BAD_VERSION),
        (gen.encode_frame(gen.SetRopeSpeed(4000), 3)[:-1], gen.NackReason.TRUNCATED),
        (gen.encode_frame(gen.SetRopeSpeed(4000), 3) + b"\x00", gen.NackReason.BAD_LENGTH),
        (bytes(b ^ (0x10 if i == 8 else 0) for i, b in enumerate(gen.encode_frame(gen.SetRopeSpeed(4000), 3))),
         gen.NackReason.BAD_CHECKSUM),
    ],
    ids=["one_byte", "garbage", "huge", "truncated", "trailing", "corrupted"],
)
def test_malformed_datagram_is_refused_counted_and_harmless(host: ScriptedHost, data: bytes,
                                                           reason: gen.NackReason) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    before = host.last_telemetry
    nack = _raw_verdict(host, data)
    assert nack.reason == reason
    host.run_for(0.1)
    after = host.last_telemetry
    assert after.rx_bad == before.rx_bad + 1
    assert after.state == gen.State.AIRBORNE and after.rope_speed_target_mmps == 5000


def test_signed_frame_of_the_wrong_direction_is_refused(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    before = host.last_telemetry
    host.send(gen.Telemetry(*([0] * len(gen.Telemetry.FIELDS))))
    host.run_for(0.1)
    assert host.received.nacks[-1].reason == gen.NackReason.NOT_A_COMMAND
    assert host.last_telemetry.rx_bad == before.rx_bad + 1 and host.last_telemetry.state == gen.State.AIRBORNE


def test_empty_datagram_reads_as_none_as_on_the_board(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    before = host.last_telemetry
    host.send_raw(b"")
    host.run_for(0.1)
    after = host.last_telemetry
    assert not host.received.nacks and after.rx_bad == before.rx_bad and after.state == gen.State.AIRBORNE


def test_out_of_range_speed_is_refused_with_the_limit_not_clamped(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    for mmps, limit in ((25_000, 20_000), (-1, 1), (0, 1)):
        nack = host.command(gen.SetRopeSpeed(mmps))
        assert isinstance(nack, gen.Nack) and nack.reason == gen.NackReason.OUT_OF_RANGE and nack.detail == limit
    host.run_for(0.1)
    assert host.last_telemetry.rope_speed_target_mmps == 5000


def test_tov_guard_refuses_a_low_setpoint_while_airborne(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    nack = host.command(gen.SetRopeSpeed(2000))
    assert isinstance(nack, gen.Nack) and nack.reason == gen.NackReason.BELOW_TOV_GUARD and nack.detail == 2990
    assert isinstance(host.command(gen.SetRopeSpeed(2990)), gen.Ack)  # exactly at the guard is allowed


def test_parameters_are_range_checked_and_locked_while_armed(host: ScriptedHost) -> None:
    radius = gen.PARAMS_BY_NAME["wheel_radius_m"].id
    kp = gen.PARAMS_BY_NAME["speed_kp"].id
    assert host.command(gen.ParamSet(kp, 5.0)).reason == gen.NackReason.OUT_OF_RANGE
    assert host.command(gen.ParamSet(kp, float("nan"))).reason == gen.NackReason.OUT_OF_RANGE
    assert host.command(gen.ParamSet(200, 1.0)).reason == gen.NackReason.UNKNOWN_PARAM
    assert isinstance(host.command(gen.Arm()), gen.Ack)
    assert host.command(gen.ParamSet(radius, 0.02)).reason == gen.NackReason.PARAM_LOCKED
    assert isinstance(host.command(gen.ParamSet(kp, 0.05)), gen.Ack)
    host.run_for(0.01)
    assert host.received.param_values[-1] == gen.ParamValue(kp, pytest.approx(0.05), len(gen.PARAMS))


def test_network_duplicate_of_a_command_is_not_executed_twice(host: ScriptedHost) -> None:
    host.arm_and_spin(5000, settle_s=1.0)
    first = host.frame(gen.SetRopeSpeed(7000), 500)
    host.send_raw(first)
    host.run_for(0.01)
    assert isinstance(host.command(gen.SetRopeSpeed(6000)), gen.Ack)
    host.send_raw(first)  # the network delivers a late copy of the 7 m/s command
    host.run_for(0.2)
    t = host.last_telemetry
    assert t.rope_speed_target_mmps == 6000 and t.rx_replayed == 1  # its counter is old: dropped
    assert len([a for a in host.received.acks if a.cmd_seq == 500]) == 1


def test_arm_is_refused_during_the_esc_arming_hold(native_build_dir) -> None:
    from robowrangler_sim.sil import SilSession

    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.1)
        nack = host.command(gen.Arm())
        assert isinstance(nack, gen.Nack) and nack.reason == gen.NackReason.NOT_READY
        host.run_for(0.5)
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        host.close()
