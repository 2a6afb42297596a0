"""Waves on the moving rope: a pluck splits into two pulses that travel at v - c and v + c in the lab,
c = sqrt(T / lambda) (transport plus waves).

Two experiments. ``measure_wave_speeds``: the span rig (ModuleGeometry.span_m > 0), where the rope
leaves the exit eyelet along e1 and runs straight to a second eyelet ``span_m`` ahead, without
gravity and air, at a tension T set by how much shorter the rope is than the span.
``measure_waves_on_loop``: the flying loop itself, where T varies along the rope.

The pluck is a sideways Gaussian bump (out of the loop plane) that leaves the material velocity
unchanged, so in the material frame it splits into two equal halves. The pulses are the two largest
separated maxima of the sideways displacement; a pulse's lab speed is the slope of a straight line
fitted to its positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import StringShooter
from .motion import ModuleMotion
from .params import AirParams, ModuleGeometry, NumericsParams, RopeParams, ShooterParams, StringShooterParamError


@dataclass(frozen=True)
class WaveResult:
    """Measured and predicted pulse speeds in the lab frame, m/s (slow first).

    Attributes:
        rope_speed_mps: v, transport speed of the material.
        tension_n: mean segment tension T measured before the pluck.
        wave_speed_mps: c = sqrt(T / lambda).
        measured_mps: shape (2,), lab speeds of the slow and the fast pulse.
        predicted_mps: shape (2,), v - c and v + c.
    """

    rope_speed_mps: float
    tension_n: float
    wave_speed_mps: float
    measured_mps: np.ndarray
    predicted_mps: np.ndarray

    @property
    def relative_error(self) -> np.ndarray:
        """|measured - predicted| / (v + c) per pulse."""
        return np.abs(self.measured_mps - self.predicted_mps) / (self.rope_speed_mps + self.wave_speed_mps)


def measure_wave_speeds(*, rope_speed_mps: float, wave_speed_mps: float, span_m: float = 3.0,
                        segment_length_m: float = 0.01, width_m: float = 0.05,
                        rope: RopeParams | None = None) -> WaveResult:
    """Run the span rig at rope speed v with tension lambda c^2 and measure the two pulse speeds.

    Bending stiffness is set to zero (a string); the axial stiffness is that of ``rope``.
    """
    if not (np.isfinite(rope_speed_mps) and rope_speed_mps > 0):
        raise StringShooterParamError(f"rope_speed_mps: expected > 0, got {rope_speed_mps!r}")
    if not (np.isfinite(wave_speed_mps) and wave_speed_mps > 0):
        raise StringShooterParamError(f"wave_speed_mps: expected > 0, got {wave_speed_mps!r}")
    rope = (rope or RopeParams()).with_(bending_stiffness_n_m2=0.0)
    lam = rope.linear_density_kg_per_m
    strain = lam * wave_speed_mps ** 2 / rope.axial_stiffness_n
    params = ShooterParams(rope=rope, air=AirParams(density_kg_per_m3=0.0),
                           geometry=ModuleGeometry(span_m=span_m, exit_offset_m=0.0, return_offset_m=0.0),
                           numerics=NumericsParams(segment_length_m=segment_length_m), gravity_mps2=0.0)
    span = span_m  # exit and return are span_m apart on the axis
    sim = StringShooter(params, loop_length_m=span / (1.0 + strain), initial_shape="straight",
                        motion=ModuleMotion(wheel_speed_mps=rope_speed_mps))
    sim.step_for(0.2)
    tension = float(np.mean(sim.segment_tensions_n()))
    c = math.sqrt(max(tension, 0.0) / lam)
    # pluck at the material now at 40 % of the span
    frame = sim.frame()
    x_nodes = frame.points_m[1:-1, 0] - frame.points_m[0, 0]
    x0 = 0.4 * span
    label0 = float(np.interp(x0, x_nodes, frame.labels_m))
    amp = 0.002
    sim.pluck(label_m=label0, amplitude_m=amp, direction=(0.0, 1.0, 0.0), width_m=width_m)
    # follow the pulses until the fast one nears the end
    fast = rope_speed_mps + c
    t_end = min(0.9 * (span - x0) / fast, 0.9 * x0 / max(c - rope_speed_mps, 1e-9))
    dt_frame = t_end / 60
    times, slow_x, fast_x = [], [], []
    for i in range(60):
        sim.step_for(dt_frame)
        f = sim.frame()
        x = f.points_m[:, 0] - f.points_m[0, 0]
        y = f.points_m[:, 1] - f.points_m[0, 1]
        times.append(f.time_s)
        slow_x.append(x), fast_x.append(y)
    times = np.asarray(times) - times[0]
    pos_slow, pos_fast, keep = [], [], []
    sep_time = 3.0 * width_m / max(c, 1e-9)  # pulses separated by a few widths
    for t, x, y in zip(times, slow_x, fast_x):
        if t < sep_time:
            continue
        pair = _two_pulses(x, np.abs(y), min_gap_m=3.0 * width_m)
        if pair is None:
            continue
        i_slow, i_fast = pair
        pos_slow.append(_peak_x(x, y, i_slow)), pos_fast.append(_peak_x(x, y, i_fast)), keep.append(t)
    keep = np.asarray(keep)
    if keep.size < 5:
        raise StringShooterParamError("span_m: too short to follow the pulses; expected a longer span")
    v_slow = float(np.polyfit(keep, pos_slow, 1)[0])
    v_fast = float(np.polyfit(keep, pos_fast, 1)[0])
    return WaveResult(rope_speed_mps=rope_speed_mps, tension_n=tension, wave_speed_mps=c,
                      measured_mps=np.array([v_slow, v_fast]),
                      predicted_mps=np.array([rope_speed_mps - c, rope_speed_mps + c]))


def _two_pulses(x: np.ndarray, a: np.ndarray, *, min_gap_m: float):
    """Indices of the two largest local maxima of a (at least min_gap_m apart in x, the smaller one at
    least a fifth of the larger), upstream one first; x must grow with the index."""
    inner = np.arange(1, a.size - 1)
    peaks = inner[(a[inner] >= a[inner - 1]) & (a[inner] >= a[inner + 1])]
    if peaks.size < 2:
        return None
    order = peaks[np.argsort(a[peaks])[::-1]]
    first = order[0]
    for p in order[1:]:
        if abs(x[p] - x[first]) >= min_gap_m and a[p] > 0.2 * a[first]:
            return (int(min(first, p)), int(max(first, p)))  # x grows with the index
    return None


def _peak_x(x: np.ndarray, y: np.ndarray, i: int) -> float:
    """Sub-node position of an extremum: parabola through the extremum and its neighbours."""
    if 0 < i < x.size - 1:
        y0, y1, y2 = y[i - 1], y[i], y[i + 1]
        den = y0 - 2 * y1 + y2
        if abs(den) > 1e-15:
            off = 0.5 * (y0 - y2) / den
            if -1 < off < 1:
                return float(x[i] + off * 0.5 * (x[i + 1] - x[i - 1]))
    return float(x[i])


@dataclass(frozen=True)
class LoopWaveResult:
    """A pluck on the airborne loop: mean lab speeds along the loop, measured and predicted, m/s.

    Attributes:
        start_arc_m: arc length from the exit where the pluck was centred.
        tension_n: local tension there before the pluck.
        measured_mps: shape (2,), mean speeds (along the loop, from the exit) of the slow and fast pulse
            over the tracking window.
        predicted_mps: shape (2,), the same from integrating ds/dt = v -+ sqrt(T(s)/lambda) over the
            steady tension profile T(s) measured before the pluck.
        window_s: (start, end) of the tracking window after the pluck, seconds.
    """

    start_arc_m: float
    tension_n: float
    rope_speed_mps: float
    measured_mps: np.ndarray
    predicted_mps: np.ndarray
    window_s: tuple


def _arc(points: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])


def measure_waves_on_loop(params: ShooterParams | None = None, *, rope_speed_mps: float = 5.0,
                          loop_length_m: float = 2.0, start_fraction: float = 0.6, width_m: float = 0.04,
                          window_s: tuple | None = None, settle_s: float = 4.0) -> LoopWaveResult:
    """Pluck the flying loop out of its plane and follow the two pulses along it.

    The loop flies at phi = 0 with gravity and air; the pluck (5 mm, sideways) is centred at
    ``start_fraction`` of the loop's arc length from the exit (on the returning branch by default).
    ``window_s`` (start, end) after the pluck; by default from when the pulses are three widths apart
    until the fast one would be 80 % of the way to the return eyelet.
    """
    params = params or ShooterParams()
    if not 0.1 <= start_fraction <= 0.9:
        raise StringShooterParamError(f"start_fraction: expected in [0.1, 0.9], got {start_fraction!r}")
    sim = StringShooter(params, loop_length_m=loop_length_m, motion=ModuleMotion(wheel_speed_mps=rope_speed_mps))
    sim.step_for(settle_s)
    frame = sim.frame()
    s_nodes = _arc(frame.points_m)[1:-1]
    ten = sim.segment_tensions_n()  # flow order, segment k between node k and k+1 (exit side first)
    s_seg = 0.5 * (s_nodes[:-1] + s_nodes[1:])
    lam = params.rope.linear_density_kg_per_m
    s0 = start_fraction * s_nodes[-1]
    t0_n = float(np.interp(s0, s_seg, ten))
    label0 = float(np.interp(s0, s_nodes, frame.labels_m))
    if window_s is None:
        c0 = np.sqrt(max(t0_n, 1e-9) / lam)
        window_s = (3.0 * width_m / c0, 0.8 * (s_nodes[-1] - s0) / (rope_speed_mps + c0))
    sim.pluck(label_m=label0, amplitude_m=0.005, direction=(0.0, 1.0, 0.0), width_m=width_m)
    t_start = sim.time_s
    frames_dt = 0.001
    n_frames = int(round(window_s[1] / frames_dt))
    times, slow, fast = [], [], []
    for _ in range(n_frames):
        sim.step_for(frames_dt)
        f = sim.frame()
        t = f.time_s - t_start
        if t < window_s[0] - 1e-9:
            continue
        s = _arc(f.points_m)
        y = f.points_m[:, 1] - f.points_m[0, 1]
        pair = _two_pulses(s, np.abs(y), min_gap_m=3.0 * width_m)
        if pair is None:
            continue
        times.append(t)
        slow.append(_peak_x(s, np.abs(y), pair[0]))
        fast.append(_peak_x(s, np.abs(y), pair[1]))
    if len(times) < 5:
        raise StringShooterParamError("window_s: expected a window in which both pulses can be followed")
    times = np.asarray(times)
    measured = np.array([np.polyfit(times, slow, 1)[0], np.polyfit(times, fast, 1)[0]])
    # prediction: integrate both characteristics through the steady tension profile
    c_of_s = lambda s: np.sqrt(max(float(np.interp(s, s_seg, ten)), 0.0) / lam)  # noqa: E731
    dt = 1e-4
    pred = []
    for sign in (-1.0, 1.0):
        s, path_t, path_s = s0, [], []
        for i in range(int(round(window_s[1] / dt))):
            s += dt * (rope_speed_mps + sign * c_of_s(s))
            tt = (i + 1) * dt
            if tt >= window_s[0] - 1e-12:
                path_t.append(tt)
                path_s.append(s)
        pred.append(np.polyfit(path_t, path_s, 1)[0])
    return LoopWaveResult(start_arc_m=float(s0), tension_n=t0_n, rope_speed_mps=rope_speed_mps,
                          measured_mps=measured, predicted_mps=np.array(pred), window_s=tuple(window_s))
