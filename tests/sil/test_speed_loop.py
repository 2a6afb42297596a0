"""The rope speed loop end to end: SIL firmware + drive plant over real UDP, judged from telemetry."""

from __future__ import annotations

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.metrics import settle_time_s
from robowrangler_sim.sil.scripted_host import ScriptedHost

GUARD_MMPS = 2600 * 1.15


def airborne_speeds_after(host: ScriptedHost, start_ms: int) -> list[int]:
    return [t.rope_speed_mmps for t in host.received.telemetry
            if t.time_ms >= start_ms and t.state == gen.State.AIRBORNE]


def test_spin_up_to_4_mps_settles_within_2_percent_in_under_a_second(host: ScriptedHost) -> None:
    assert isinstance(host.command(gen.Arm()), gen.Ack)
    start_ms = host.last_telemetry.time_ms
    assert isinstance(host.command(gen.SetRopeSpeed(4000)), gen.Ack)
    host.run_for(2.0)
    times, speeds = host.telemetry_series("rope_speed_mmps", since_ms=start_ms)
    settle = settle_time_s(times, speeds, target=4000, start_s=start_ms / 1000.0)
    assert settle is not None and settle < 1.0, f"settle time {settle}"
    assert abs(host.sil.plant.rope_speed_mps - 4.0) < 0.08  # the plant agrees with the telemetry
    assert host.last_telemetry.state == gen.State.AIRBORNE


def test_step_from_4_to_6_mps_settles_and_never_leaves_the_guard(host: ScriptedHost) -> None:
    host.arm_and_spin(4000)
    airborne_ms = next(e.time_ms for e in host.received.events
                       if e.event == gen.EventKind.STATE_CHANGED and e.state_to == gen.State.AIRBORNE)
    step_ms = host.last_telemetry.time_ms
    assert isinstance(host.command(gen.SetRopeSpeed(6000)), gen.Ack)
    host.run_for(1.5)
    times, speeds = host.telemetry_series("rope_speed_mmps", since_ms=step_ms)
    settle = settle_time_s(times, speeds, target=6000, start_s=step_ms / 1000.0)
    assert settle is not None and settle < 1.0
    assert min(airborne_speeds_after(host, airborne_ms + 100)) >= GUARD_MMPS


def test_rope_load_disturbance_is_rejected(host: ScriptedHost) -> None:
    host.arm_and_spin(6000)
    load_ms = host.last_telemetry.time_ms
    host.sil.set_rope_load(4.0)  # N, the rope dragging on an obstacle
    host.run_for(1.5)
    times, speeds = host.telemetry_series("rope_speed_mmps", since_ms=load_ms)
    assert min(speeds) < 5900, "the load should be felt (else this test proves nothing)"
    assert min(speeds) >= GUARD_MMPS
    assert abs(speeds[-1] - 6000) <= 120  # back within 2 % under the load
    pulses = [t.esc_pulse_us for t in host.received.telemetry if t.time_ms >= load_ms]
    assert pulses[-1] > pulses[0]  # the integrator found the extra throttle


def test_spindown_lands_the_rope_and_ends_armed(host: ScriptedHost) -> None:
    host.arm_and_spin(6000)
    assert isinstance(host.command(gen.Spindown()), gen.Ack)
    stopped = host.run_until(lambda h: h.last_telemetry.state == gen.State.ARMED, timeout_s=3.0)
    assert stopped
    assert host.sil.plant.rope_speed_mps < 0.2
    assert isinstance(host.command(gen.Disarm()), gen.Ack)
    host.run_for(0.05)
    assert host.last_telemetry.state == gen.State.DISARMED


def test_estop_cuts_the_throttle_at_once_and_latches(host: ScriptedHost) -> None:
    host.arm_and_spin(6000)
    assert isinstance(host.command(gen.Estop()), gen.Ack)
    host.run_for(0.03)
    t = host.last_telemetry
    assert t.state == gen.State.ESTOP and t.esc_pulse_us == 1000
    refused = host.command(gen.SetRopeSpeed(4000))
    assert isinstance(refused, gen.Nack) and refused.reason == gen.NackReason.BAD_STATE
    early = host.command(gen.Disarm())  # rope still coasting
    assert isinstance(early, gen.Nack) and early.reason == gen.NackReason.BAD_STATE
    host.run_until(lambda h: h.sil.plant.rope_speed_mps < 0.1, timeout_s=5.0)
    host.run_for(0.2)
    assert isinstance(host.command(gen.Disarm()), gen.Ack)


def test_heartbeat_loss_spins_down_within_the_timeout(host: ScriptedHost) -> None:
    host.arm_and_spin(6000)
    host.heartbeats_enabled = False
    last_frame_ms = host.last_sent_us // 1000
    host.run_for(2.0)
    spindown = next(e for e in host.received.events
                    if e.event == gen.EventKind.STATE_CHANGED and e.state_to == gen.State.SPINDOWN)
    assert spindown.arg == gen.Cause.HEARTBEAT_LOST
    assert spindown.time_ms - last_frame_ms <= 500 + 2  # heartbeat_timeout_s + one tick
    assert any(e.event == gen.EventKind.HEARTBEAT_LOST for e in host.received.events)
    assert host.last_telemetry.state == gen.State.ARMED
    assert host.sil.plant.rope_speed_mps < 0.2


def test_stalled_rope_reports_loop_collapse_then_encoder_fault(host: ScriptedHost) -> None:
    collapse_param = gen.PARAMS_BY_NAME["collapse_time_s"].id
    assert isinstance(host.command(gen.ParamSet(collapse_param, 0.05)), gen.Ack)
    host.arm_and_spin(4000)
    stall_ms = host.last_telemetry.time_ms
    host.sil.set_rope_load(400.0)  # N: far more than the ESC current limit lets the motors pull: the rope stops
    host.run_for(1.0)
    kinds = [(e.time_ms, gen.EventKind(e.event)) for e in host.received.events if e.time_ms >= stall_ms]
    collapsed = [t for t, k in kinds if k == gen.EventKind.LOOP_COLLAPSED]
    fault = [t for t, k in kinds if k == gen.EventKind.FAULT_RAISED]
    assert len(collapsed) == 1 and len(fault) == 1
    assert collapsed[0] - stall_ms <= 50 + 100  # under ToV within a few ms, then collapse_time_s
    assert fault[0] > collapsed[0]  # then the encoder falls silent with the throttle up
    t = host.last_telemetry
    assert t.state == gen.State.FAULT and t.fault_bits & gen.Fault.ENCODER_SILENT and t.esc_pulse_us == 1000


def test_esc_pulse_stays_within_esc_range_through_a_whole_run(host: ScriptedHost) -> None:
    host.arm_and_spin(6000)
    host.command(gen.SetRopeSpeed(20000))
    host.run_for(1.0)
    host.command(gen.Spindown())
    host.run_for(2.0)
    pulses = [t.esc_pulse_us for t in host.received.telemetry]
    assert min(pulses) == 1000 and max(pulses) <= 2000
    assert max(pulses) > 1800  # 20 m/s really pushed the throttle
