"""Run a checked excitation profile with a connected Client.

    limits = Limits.from_params(read_device_params(client.get_param))
    result = run_profile(client, load_profile("drive"), limits=limits, progress=print)

Sequence: check the profile against the limits (ProfileError before anything moves); ARM; HOME with the rope
stopped if a step moves the guide; the steps in order, timed on the device's clock (telemetry time_s, so a SIL
runs them right at any speed-up); then land: SPINDOWN if the rope is driven, wait for ARMED, wait (up to
BURST_TAIL_S of device time) until the frames of every burst asked have arrived, DISARM. The landing runs also
when a step fails or the run is interrupted (Ctrl-C: KeyboardInterrupt), as far as the link allows; the device
itself spins down on heartbeat loss if the link is gone. Every command goes through the Client: the firmware's
own checks apply (a NACK raises CommandRefused and the run lands).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from robowrangler.client import Client
from robowrangler.errors import RoboWranglerError
from robowrangler.excite.profile import Limits, Profile, Step, check_limits
from robowrangler.protocol.generated import BURST_SAMPLES_PER_FRAME, SpindleFlag, State

HOME_TIMEOUT_S = 60.0
SLOWEST_SIM_SPEEDUP = 0.25  # device time may run this slow against the wall clock (a slow SIL) before a wait fails
BURST_TAIL_S = 10.0  # device time allowed for the last bursts' frames to arrive after the landing
GUIDE_REACHED_M = 1e-3  # a loop step is done when the guide is this close to its target
_DRIVEN = (State.SPINUP, State.AIRBORNE, State.RELAX)


@dataclass
class ExciteResult:
    """What a run did: steps completed, bursts asked and their frames received, device time taken, whether it was
    interrupted, the state it ended in."""

    profile: str
    steps_done: int
    steps_total: int
    bursts: int = 0
    burst_frames_expected: int = 0
    burst_frames_received: int = 0
    duration_s: float = 0.0
    interrupted: bool = False
    final_state: str = ""
    notes: list[str] = field(default_factory=list)


def _now_s(client: Client) -> float:
    sample = client.latest_telemetry
    if sample is None:
        sample = client.wait_for(lambda s: True, timeout_s=client.connect_timeout_s, expected="telemetry")
    return sample.time_s


def _wait_device_time(client: Client, until_s: float) -> None:
    remaining = until_s - _now_s(client)
    if remaining <= 0:
        return
    client.wait_for(lambda s: s.time_s >= until_s, timeout_s=remaining / SLOWEST_SIM_SPEEDUP + 5.0,
                    expected=f"device time {until_s:.3f} s")


def _setpoints(client: Client, step: Step, value_at: Callable[[float], float]) -> float:
    """Send value_at(t) (t from 0 to duration) at update_hz on the device's clock; returns the last value."""
    t0 = _now_s(client)
    n = max(1, math.ceil(step.duration_s * step.update_hz))
    last = value_at(0.0)
    for k in range(n + 1):
        t = min(step.duration_s, k / step.update_hz)
        _wait_device_time(client, t0 + t)
        last = value_at(t)
        client.spin(last)
    return last


def _run_step(client: Client, step: Step, speed_mps: float | None, guide_tolerance_m: float) -> float | None:
    """One step; returns the speed set point after it (None: rope landed)."""
    if step.kind == "speed":
        client.spin(step.speed_mps)
        _wait_device_time(client, _now_s(client) + step.hold_s)
        return step.speed_mps
    if step.kind == "ramp":
        start = step.to_mps if speed_mps is None else speed_mps
        return _setpoints(client, step, lambda t: start + (step.to_mps - start) * t / step.duration_s)
    if step.kind == "chirp":
        rate = (step.f1_hz - step.f0_hz) / step.duration_s
        return _setpoints(client, step, lambda t: step.center_mps + step.amplitude_mps * math.sin(
            2 * math.pi * (step.f0_hz * t + 0.5 * rate * t * t)))
    if step.kind == "hold":
        _wait_device_time(client, _now_s(client) + step.duration_s)
        return speed_mps
    if step.kind == "loop":
        target_m = step.guide_mm * 1e-3
        client.set_loop(target_m)
        client.wait_for(lambda s: abs(s.guide_position_m - target_m) <= guide_tolerance_m,
                        timeout_s=step.timeout_s / SLOWEST_SIM_SPEEDUP, expected=f"guide at {step.guide_mm:g} mm")
        return speed_mps
    if step.kind == "burst":
        client.start_burst(int(step.samples))
        return speed_mps
    if step.kind == "spindown":
        client.spindown()
        client.wait_for_state(State.ARMED, timeout_s=step.timeout_s / SLOWEST_SIM_SPEEDUP)
        return None
    raise ValueError(f"step kind {step.kind!r}")  # load_profile admits no other


def run_profile(client: Client, profile: Profile, *, limits: Limits,
                progress: Callable[[str], None] | None = None) -> ExciteResult:
    """Run profile (checked against limits first) on a connected client; see the module docstring."""
    check_limits(profile, limits)
    say = progress or (lambda _text: None)
    result = ExciteResult(profile.name, 0, len(profile.steps))
    frames0 = client.stats.burst_frames
    start_s = _now_s(client)
    try:
        client.arm(timeout_s=client.connect_timeout_s)
        if profile.needs_home:
            say("homing the spindle (rope stopped)")
            client.home()
            client.wait_for(lambda s: SpindleFlag.HOMED in s.spindle_flags and SpindleFlag.HOMING not in s.spindle_flags,
                            timeout_s=HOME_TIMEOUT_S / SLOWEST_SIM_SPEEDUP, expected="a homed spindle")
        speed: float | None = None
        for step in profile.steps:
            say(f"step {step.index}/{len(profile.steps)}: {step.kind} "
                + " ".join(f"{k}={v:g}" for k, v in step.values.items()))
            speed = _run_step(client, step, speed, GUIDE_REACHED_M)
            if step.kind == "burst":
                result.bursts += 1
                result.burst_frames_expected += math.ceil(step.samples / BURST_SAMPLES_PER_FRAME)
            result.steps_done += 1
    except KeyboardInterrupt:
        result.interrupted = True
        say("interrupted: landing the rope")
    finally:
        _land(client, result, say, frames0)
    result.duration_s = max(0.0, _now_s(client) - start_s) if client.connected else result.duration_s
    if result.interrupted:
        raise KeyboardInterrupt
    return result


def _land(client: Client, result: ExciteResult, say: Callable[[str], None], frames0: int) -> None:
    """SPINDOWN if the rope is driven, wait ARMED, let the bursts' frames arrive, DISARM (best effort: an error
    here is a note, the first error of the run is what propagates)."""
    if not client.connected:
        return
    try:
        latest = client.latest_telemetry
        if latest is not None and latest.state in _DRIVEN:
            client.spindown()
        client.wait_for_state((State.ARMED, State.DISARMED, State.FAULT, State.ESTOP), timeout_s=60.0)
        expected = result.burst_frames_expected
        if expected:
            deadline = _now_s(client) + BURST_TAIL_S
            while client.stats.burst_frames - frames0 < expected and _now_s(client) < deadline:
                client.wait_for(lambda s: True, timeout_s=client.connect_timeout_s, expected="telemetry")
        result.burst_frames_received = client.stats.burst_frames - frames0
        result.final_state = client.disarm().name
    except RoboWranglerError as err:
        result.notes.append(f"landing: {err}")
        say(f"landing: {err}")
