"""rw_core safety supervision: heartbeat loss (spin-down while the rope is driven, event only while
ARMED), encoder silence with the throttle up (FAULT, ENCODER_SILENT, ESC to esc_min), the ESC pulse
never under esc_min_us."""

from __future__ import annotations

import pytest

from core_harness import CoreHarness
from robowrangler.protocol.generated import (
    PARAMS_BY_NAME, Ack, Arm, Cause, NackReason, Disarm, Estop, EventKind, Fault, ParamSet, SetRopeSpeed, Spindown, State,
)

S = State
P = PARAMS_BY_NAME


def _silent_host(h: CoreHarness, ms: int) -> None:
    """The rope keeps following the setpoint; the host sends nothing."""
    for _ in range(ms):
        tel = h.telemetry()
        if tel:
            h.encoder.speed_mps = tel[-1].rope_speed_setpoint_mmps / 1000.0
        h.tick()


def _last_host_frame_ms(h: CoreHarness) -> int:
    h.heartbeat()
    h.tick()
    return h.t_ms


@pytest.mark.parametrize("timeout_s", [0.5, 2.0])
@pytest.mark.parametrize("state", [S.SPINUP, S.AIRBORNE])
def test_heartbeat_loss_spins_down_exactly_after_the_timeout(rw_core, state, timeout_s):
    h = CoreHarness(rw_core, params={"heartbeat_timeout_s": timeout_s})
    h.boot_and_arm()
    if state == S.AIRBORNE:
        h.spin_to_airborne(target_mmps=4000)
    else:
        h.command(SetRopeSpeed(2000))
        h.follow_setpoint(until=lambda: h.telemetry()[-1].rope_speed_setpoint_mmps > 1000, max_ms=500, what="ramp")
    t_last = _last_host_frame_ms(h)
    timeout_ms = round(timeout_s * 1000)
    _silent_host(h, timeout_ms - 1)
    # the state itself, not after a drain: a frame being signed may take a few more ticks to leave (up to 6 when
    # its telemetry tick meets the spindle slot), which would carry a drain past the timeout
    assert h.state == state and h.events(EventKind.HEARTBEAT_LOST) == [], "not before the timeout"
    _silent_host(h, 10)
    lost = h.events(EventKind.HEARTBEAT_LOST)
    assert len(lost) == 1
    assert timeout_ms < lost[0].time_ms - t_last <= timeout_ms + 1, "the first tick past the timeout"
    assert lost[0].arg == lost[0].time_ms - t_last, "arg = silence, ms"
    t, f, to, cause = h.transitions()[-1]
    assert (t, f, to, cause) == (lost[0].time_ms, state, S.SPINDOWN, Cause.HEARTBEAT_LOST)
    # The spin-down completes on its own, ending ARMED, ESC back at its minimum.
    _silent_host(h, 1500)
    assert h.transitions()[-1][1:] == (S.SPINDOWN, S.ARMED, Cause.SPEED_REACHED)
    assert h.pulse_us == 1000
    assert len(h.events(EventKind.HEARTBEAT_LOST)) == 1, "reported once per silence"


def test_forced_spindown_reports_a_zero_target(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=3000, what="heartbeat-loss landing",
                      heartbeat_ms=None)
    h.drain(25)
    tel = h.telemetry()[-1]
    assert tel.state == S.ARMED
    assert tel.rope_speed_target_mmps == 0, "ARMED with the rope landed, yet the target still reads 4 m/s"


def test_heartbeat_one_tick_before_the_timeout_keeps_the_rope_flying(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    for _ in range(5):
        _last_host_frame_ms(h)
        _silent_host(h, 499)
    _last_host_frame_ms(h)
    h.drain(3)
    assert h.state == S.AIRBORNE and h.events(EventKind.HEARTBEAT_LOST) == []


def test_heartbeat_loss_while_armed_only_reports(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    t_last = h.t_ms
    h.drain(3)
    n_tr = len(h.transitions())
    h.run_ms(3000)
    lost = h.events(EventKind.HEARTBEAT_LOST)
    assert len(lost) == 1 and 500 < lost[0].time_ms - t_last <= 501
    assert (lost[0].state_from, lost[0].state_to) == (S.ARMED, S.ARMED)
    assert len(h.transitions()) == n_tr, "stays ARMED"
    assert set(h.hal.pulses_us[-2990:]) == {1000}
    # The host comes back: it can command at once, and a new silence is reported again.
    assert isinstance(h.command(SetRopeSpeed(2000)), Ack)
    h.command(Spindown())
    h.run_ms(1000)
    assert len(h.events(EventKind.HEARTBEAT_LOST)) == 2


def test_no_heartbeat_event_while_disarmed(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(3000)
    assert h.events(EventKind.HEARTBEAT_LOST) == []


def _first_active_throttle_ms(h: CoreHarness, since_ms: int) -> int:
    esc_min = round(h.get_param_value("esc_min_us"))
    for t in range(since_ms, len(h.hal.pulses_us)):
        if h.hal.pulses_us[t] > esc_min + 30:
            return t
    raise AssertionError("throttle never rose above idle")


@pytest.mark.parametrize("timeout_s", [0.25, 0.1])
def test_encoder_silent_with_throttle_up_faults_after_encoder_timeout(rw_core, timeout_s):
    h = CoreHarness(rw_core, params={"encoder_timeout_s": timeout_s})
    h.boot_and_arm()
    t_cmd = h.t_ms
    h.command(SetRopeSpeed(5000))  # the encoder never moves: wheel blocked or sensor unplugged
    h.run_until(lambda: h.state == S.FAULT, max_ms=2000, what="FAULT")
    t_up = _first_active_throttle_ms(h, t_cmd)
    (raised,) = h.events(EventKind.FAULT_RAISED)
    assert raised.arg == Fault.ENCODER_SILENT
    timeout_ms = round(timeout_s * 1000)
    assert timeout_ms <= raised.time_ms - t_up <= timeout_ms + 2
    t_fault = h.transitions()[-1][0]
    assert h.transitions()[-1][1:] == (S.SPINUP, S.FAULT, Cause.FAULT)
    assert t_fault == raised.time_ms
    assert h.hal.pulses_us[t_fault - 1] > 1030 and all(p == 1000 for p in h.hal.pulses_us[t_fault:]), \
        "ESC at esc_min from the fault tick on"
    h.run_ms(100)
    tel = h.telemetry()[-1]
    assert (tel.state, tel.fault_bits, tel.esc_pulse_us) == (S.FAULT, Fault.ENCODER_SILENT, 1000)


def test_encoder_lost_while_airborne_faults_after_encoder_timeout(rw_core):
    """The encoder stops reporting mid-flight (cable pulled): FAULT after encoder_timeout_s, ESC to idle.
    Until then the loop sees a decaying speed and raises the throttle (measured: 1172 -> ~1710 us)."""
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    h.follow_setpoint(until=lambda: h.t_ms > 1200, max_ms=1000, what="steady flight")
    i_loss = len(h.hal.pulses_us)
    t_loss = h.t_ms
    h.encoder.speed_mps = 0.0  # counts freeze: the estimator sees silence
    for _ in range(400):
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    h.drain(3)
    (raised,) = h.events(EventKind.FAULT_RAISED)
    assert raised.arg == Fault.ENCODER_SILENT
    assert 250 <= raised.time_ms - t_loss <= 252
    assert h.transitions()[-1][1:] == (S.AIRBORNE, S.FAULT, Cause.FAULT)
    t_fault = raised.time_ms
    assert all(p == 1000 for p in h.hal.pulses_us[t_fault:])
    assert max(h.hal.pulses_us[i_loss:t_fault]) < 2000, "no full throttle before the fault"


def test_silent_encoder_at_idle_throttle_is_not_a_fault(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    for _ in range(2000):
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    assert h.events(EventKind.FAULT_RAISED) == [] and h.state == S.ARMED


def test_encoder_edges_keep_the_fault_away(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    h.follow_setpoint(until=lambda: h.t_ms > 2700, max_ms=2100, what="2 s airborne")
    h.drain(3)
    assert h.events(EventKind.FAULT_RAISED) == [] and h.state == S.AIRBORNE


def _run_cycle(h: CoreHarness) -> None:
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=6000)
    h.follow_setpoint(until=lambda: h.telemetry()[-1].rope_speed_setpoint_mmps >= 6000, max_ms=1000,
                      what="6 m/s")
    h.command(Spindown())
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=2000, what="ARMED")
    h.command(SetRopeSpeed(3000))
    h.run_ms(20)
    h.command(Estop())
    h.encoder.speed_mps = 0.0
    h.run_ms(300)
    h.command(Disarm())
    h.run_ms(20)


@pytest.mark.parametrize("esc_min_us", [1000.0, 1150.0, 1200.0])
def test_esc_pulse_never_under_esc_min_through_a_whole_cycle(rw_core, esc_min_us):
    h = CoreHarness(rw_core)
    h.tick()
    assert isinstance(h.command(ParamSet(P["esc_min_us"].id, esc_min_us)), Ack)
    # the PARAM_SET's tick stages it; the next tick (no datagram) converts the throttle map at its end
    h.tick()
    h.tick()
    assert h.pulse_us == esc_min_us, "the new minimum is output from the second tick after the PARAM_SET"
    _run_cycle(h)
    pulses = h.hal.pulses_us[3:]
    assert min(pulses) == esc_min_us
    assert max(pulses) > esc_min_us + 100, "the cycle really drove the ESC"
    assert max(pulses) <= 2000


def test_esc_min_under_the_esc_protocol_floor_is_refused(rw_core):
    """esc_min_us below 1000 us (the bottom of the ESC protocol) is refused, not clamped."""
    h = CoreHarness(rw_core)
    verdict = h.command(ParamSet(PARAMS_BY_NAME["esc_min_us"].id, 900.0))
    assert verdict.reason == NackReason.OUT_OF_RANGE


@pytest.mark.parametrize("esc_min_us", [1000.0, 1100.0, 1200.0])
def test_zero_throttle_while_driving_is_the_esc_idle_pulse(rw_core, esc_min_us):
    """SPINUP with the rope faster than the target: the PI goes to zero throttle = esc_min_us."""
    h = CoreHarness(rw_core, params={"esc_min_us": esc_min_us})
    h.boot_and_arm()
    h.encoder.speed_mps = 5.0  # rope already running fast (pushed, or coasting from before)
    h.run_ms(50)
    h.command(SetRopeSpeed(1000))
    for _ in range(300):
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
    assert h.telemetry()[-1].state == S.SPINUP
    assert h.pulse_us == esc_min_us


def _fly(h: CoreHarness, ms: int) -> None:
    """ms of ticks with the rope following the setpoint and the host sending heartbeats."""
    end = h.t_ms + ms
    h.follow_setpoint(until=lambda: h.t_ms >= end, max_ms=ms + 1, what=f"{ms} ms of flight")


def test_battery_under_cutoff_for_cutoff_time_lands_the_rope(rw_core):
    h = CoreHarness(rw_core)  # cutoff 9.9 V for 1.0 s (spec defaults)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    _fly(h, 50)
    t_sag = h.t_ms + 1  # the next tick reads the low voltage
    h.hal.battery_mv = 9800
    _fly(h, 990)
    assert h.events(EventKind.FAULT_RAISED) == [] and h.state == S.AIRBORNE
    _fly(h, 30)
    (raised,) = h.events(EventKind.FAULT_RAISED)
    assert raised.arg == Fault.BATTERY_LOW
    assert 999 <= raised.time_ms - t_sag <= 1001, "battery_cutoff_time_s of low readings"
    t, f, to, cause = h.transitions()[-1]
    assert (t, f, to, cause) == (raised.time_ms, S.AIRBORNE, S.SPINDOWN, Cause.BATTERY_LOW)
    reply = h.command(SetRopeSpeed(4000))
    assert reply.reason == NackReason.BAD_STATE, "no new spin-up on a flat battery"
    h.follow_setpoint(until=lambda: h.state == S.ARMED, max_ms=2000, what="landed")
    assert h.pulse_us == 1000
    h.drain(25)
    assert h.telemetry()[-1].fault_bits == Fault.BATTERY_LOW


def test_brief_battery_sags_are_ignored(rw_core):
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    for _ in range(3):
        h.hal.battery_mv = 9000
        _fly(h, 900)
        h.hal.battery_mv = 14000
        _fly(h, 5)
    h.drain(3)
    assert h.events(EventKind.FAULT_RAISED) == [] and h.state == S.AIRBORNE


def test_battery_fault_is_cleared_by_disarm_once_the_battery_is_back(rw_core):
    h = CoreHarness(rw_core, params={"battery_cutoff_time_s": 0.1})
    h.boot_and_arm()
    h.hal.battery_mv = 9000
    h.run_ms(150)
    h.heartbeat()
    h.tick()
    h.drain(25)
    assert h.telemetry()[-1].fault_bits == Fault.BATTERY_LOW
    assert h.state == S.ARMED, "a battery fault leaves ARMED alone"
    h.hal.battery_mv = 15000
    assert isinstance(h.command(Disarm()), Ack)
    h.drain(25)
    assert [e.arg for e in h.events(EventKind.FAULT_CLEARED)] == [Fault.BATTERY_LOW]
    assert h.telemetry()[-1].fault_bits == 0
    assert isinstance(h.command(Arm()), Ack)
    assert isinstance(h.command(SetRopeSpeed(3000)), Ack)
