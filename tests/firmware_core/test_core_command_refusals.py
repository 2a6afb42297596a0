"""rw_core command refusals: OUT_OF_RANGE (detail = the limit), BAD_STATE, UNKNOWN_PARAM,
BELOW_TOV_GUARD (detail = guard, mm/s), PARAM_LOCKED, NOT_READY; each counted in TELEMETRY.nacks and
changing nothing (a twin core that never got the command behaves identically)."""

from __future__ import annotations

import math

import pytest

from core_harness import CoreHarness, telemetry_without
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import (
    PARAMS_BY_NAME, Ack, Arm, Disarm, EventKind, Nack, NackReason, ParamGet, ParamSet, SetRopeSpeed, State,
)

P = PARAMS_BY_NAME


def _airborne_twins(rw_core, **kw) -> tuple[CoreHarness, CoreHarness]:
    twins = []
    for _ in range(2):
        h = CoreHarness(rw_core, **kw)
        h.boot_and_arm()
        h.spin_to_airborne(target_mmps=4000)
        h.encoder.speed_mps = 4.0
        h.heartbeat()
        h.run_ms(40)
        twins.append(h)
    return twins[0], twins[1]


def _refused_without_effect(a: CoreHarness, b: CoreHarness, msg, reason: NackReason) -> Nack:
    """a gets msg, b gets a HEARTBEAT in the same tick (both are valid host frames); 60 ms later the
    two cores must agree on everything but the nacks counter."""
    i0 = len(a.hal.out)
    events_before = len(a.events())
    nack_gap_before = a.telemetry()[-1].nacks - b.telemetry()[-1].nacks
    reply = a.command(msg)
    b.heartbeat()
    b.tick()
    for h in (a, b):
        h.run_ms(60)
    assert isinstance(reply, Nack), f"expected NACK {reason.name}, got {reply}"
    assert reply.reason == reason
    assert a.hal.pulses_us == b.hal.pulses_us, "ESC pulse unchanged"
    ta, tb = a.telemetry()[-1], b.telemetry()[-1]
    assert ta.nacks == tb.nacks + nack_gap_before + 1 and ta.rx_bad == tb.rx_bad, "a refused command counts as a NACK, not rx_bad"
    assert telemetry_without(ta, "nacks") == telemetry_without(tb, "nacks"), "state, target, setpoint unchanged"
    assert len(a.events()) == events_before, "no event (no PARAM_CHANGED, no state change)"
    assert a.sent(proto.ParamValue, since=i0) == [], "no PARAM_VALUE after a refused PARAM_SET/GET"
    return reply


@pytest.mark.parametrize("mmps, detail", [(0, 1), (-4000, 1), (-2**31, 1), (20001, 20000), (2**31 - 1, 20000)])
def test_rope_speed_out_of_range_is_refused_with_the_limit_not_clamped(rw_core, mmps, detail):
    a, b = _airborne_twins(rw_core)
    reply = _refused_without_effect(a, b, SetRopeSpeed(mmps), NackReason.OUT_OF_RANGE)
    assert reply.detail == detail
    assert reply.state == State.AIRBORNE


def test_the_speed_limit_follows_max_rope_speed_mps(rw_core):
    h = CoreHarness(rw_core, params={"max_rope_speed_mps": 8.0})
    h.boot_and_arm()
    reply = h.command(SetRopeSpeed(8001))
    assert (reply.reason, reply.detail) == (NackReason.OUT_OF_RANGE, 8000)
    assert isinstance(h.command(SetRopeSpeed(8000)), Ack), "the limit itself is accepted"


def test_below_tov_guard_detail_is_the_smallest_accepted_setpoint(rw_core):
    a, b = _airborne_twins(rw_core)
    reply = _refused_without_effect(a, b, SetRopeSpeed(2989), NackReason.BELOW_TOV_GUARD)
    assert reply.detail == 2990, "guard = 2.6 m/s x 1.15, mm/s"
    assert isinstance(a.command(SetRopeSpeed(reply.detail)), Ack), "detail itself is accepted"
    a.run_ms(30)
    assert a.telemetry()[-1].rope_speed_target_mmps == 2990


def test_below_tov_guard_follows_tov_and_margin(rw_core):
    a, b = _airborne_twins(rw_core, params={"tov_mps": 2.0, "tov_margin": 1.25})
    reply = _refused_without_effect(a, b, SetRopeSpeed(2400), NackReason.BELOW_TOV_GUARD)
    assert reply.detail == 2500


def test_bad_state_commands_change_nothing(rw_core):
    a, b = _airborne_twins(rw_core)
    for msg in (Arm(), Disarm()):
        reply = _refused_without_effect(a, b, msg, NackReason.BAD_STATE)
        assert reply.state == State.AIRBORNE


def test_set_rope_speed_while_disarmed_is_bad_state(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(600)
    reply = h.command(SetRopeSpeed(3000))
    assert (reply.reason, reply.state) == (NackReason.BAD_STATE, State.DISARMED)
    h.run_ms(100)
    assert set(h.hal.pulses_us) == {1000}
    assert h.telemetry()[-1].rope_speed_target_mmps == 0


@pytest.mark.parametrize("msg", [ParamGet(len(proto.PARAMS)), ParamGet(255), ParamSet(len(proto.PARAMS), 1.0),
                                 ParamSet(200, 0.0)])
def test_unknown_parameter_is_refused_with_its_id(rw_core, msg):
    a, b = _airborne_twins(rw_core)
    reply = _refused_without_effect(a, b, msg, NackReason.UNKNOWN_PARAM)
    assert reply.detail == msg.param_id


@pytest.mark.parametrize("name, value", [
    ("tov_mps", 10.01), ("tov_mps", 0.49), ("speed_kp", -0.01), ("telemetry_rate_hz", 0.0),
    ("telemetry_rate_hz", 100.5), ("speed_ki", math.nan), ("speed_ki", math.inf), ("ramp_up_mps2", -math.inf),
    ("heartbeat_timeout_s", 0.05), ("max_rope_speed_mps", 25.5),
])
def test_parameter_out_of_range_is_refused_not_clamped(rw_core, name, value):
    a, b = _airborne_twins(rw_core)
    before = a.get_param_value(name)
    _refused_without_effect(a, b, ParamSet(P[name].id, value), NackReason.OUT_OF_RANGE)
    assert a.get_param_value(name) == before


@pytest.mark.parametrize("value", [64.5, 0.0, 4097.0])
def test_integer_parameter_refuses_fractions_and_out_of_range(rw_core, value):
    h = CoreHarness(rw_core)
    h.tick()
    reply = h.command(ParamSet(P["encoder_counts_per_rev"].id, value))
    assert reply.reason == NackReason.OUT_OF_RANGE
    assert h.get_param_value("encoder_counts_per_rev") == 64.0


@pytest.mark.parametrize("name, value", [("esc_min_us", 1100.0), ("wheel_radius_m", 0.02),
                                         ("encoder_counts_per_rev", 32.0), ("arm_hold_s", 1.0)])
def test_locked_parameter_is_refused_while_airborne(rw_core, name, value):
    assert P[name].locked
    a, b = _airborne_twins(rw_core)
    before = a.get_param_value(name)
    reply = _refused_without_effect(a, b, ParamSet(P[name].id, value), NackReason.PARAM_LOCKED)
    assert reply.detail == P[name].id
    assert a.get_param_value(name) == before


def test_locked_parameter_is_refused_while_armed_and_accepted_while_disarmed(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    pid = P["esc_min_us"].id
    assert h.command(ParamSet(pid, 1100.0)).reason == NackReason.PARAM_LOCKED
    assert isinstance(h.command(Disarm()), Ack)
    assert isinstance(h.command(ParamSet(pid, 1100.0)), Ack)
    assert h.get_param_value("esc_min_us") == 1100.0


def test_unlocked_parameter_is_accepted_while_airborne_with_event_and_value(rw_core):
    a, _ = _airborne_twins(rw_core)
    i0 = len(a.hal.out)
    reply = a.command(ParamSet(P["speed_kp"].id, 0.05))
    assert isinstance(reply, Ack) and reply.state == State.AIRBORNE
    a.drain(5)
    values = a.sent(proto.ParamValue, since=i0)
    assert len(values) == 1
    assert values[0].msg.param_id == P["speed_kp"].id
    assert values[0].msg.value == pytest.approx(0.05)
    assert values[0].msg.param_count == len(proto.PARAMS)
    changed = [e for e in a.events() if e.event == EventKind.PARAM_CHANGED]
    assert [e.arg for e in changed] == [P["speed_kp"].id]


def test_param_get_answers_ack_then_the_value(rw_core):
    h = CoreHarness(rw_core, params={"tov_mps": 3.25})
    h.tick()
    i0 = len(h.hal.out)
    reply = h.command(ParamGet(P["tov_mps"].id))
    assert isinstance(reply, Ack)
    h.drain(3)
    (value,) = h.sent(proto.ParamValue, since=i0)
    assert (value.msg.param_id, value.msg.value) == (P["tov_mps"].id, 3.25)


def test_not_ready_is_counted_and_arms_nothing(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(100)
    for _ in range(3):
        assert h.command(Arm()).reason == NackReason.NOT_READY
    h.run_ms(300)
    tel = h.telemetry()[-1]
    assert (tel.state, tel.nacks, tel.rx_ok, tel.rx_bad) == (State.DISARMED, 3, 3, 0)
    assert set(h.hal.pulses_us) == {1000}


@pytest.mark.parametrize("name, value", [("tov_margin", 1.6), ("tov_mps", 3.8)])
def test_raising_the_guard_while_airborne_never_leaves_the_target_under_it(rw_core, name, value):
    a, _ = _airborne_twins(rw_core)  # target 4 m/s, guard 2.99 m/s
    a.command(ParamSet(P[name].id, value))
    a.run_ms(30)
    tel = a.telemetry()[-1]
    guard_mmps = math.ceil(a.get_param_value("tov_mps") * a.get_param_value("tov_margin") * 1000.0 - 0.5)
    assert tel.state != State.AIRBORNE or tel.rope_speed_target_mmps >= guard_mmps, \
        f"AIRBORNE with target {tel.rope_speed_target_mmps} mm/s under the guard {guard_mmps} mm/s"
