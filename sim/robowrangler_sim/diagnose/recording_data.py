"""The drive channels of one recording, checked and laid on the 1 ms tick grid the replay runs on.

Reads /device/telemetry and /device/burst (never /sim/plant_truth: a board has none) and /device/params when
present. What the engine compares (the *observations*, one axis in time order):

* rope speed: where the records carry the encoder's edge count and latest edge time (telemetry at 50-100 Hz,
  and every 1 ms sample of a burst), the mean rope speed over exactly the edges counted between two records
  (edges x 2 pi r / counts_per_rev over the time between their latest edges): unfiltered, and exact up to the
  1 us edge clock, so the model is compared on the rope's travel between two edge times. Without encoder
  fields (an outside writer that has none), the telemetry's filtered ``rope_speed_mps``. A record that saw no
  new edge for REST_GAP_S or more (the rope at or near rest) observes an interval, not a value: the rope
  travelled less than the distance to the next edge since its last one, so the mean speed since that edge lies in
  [0, ``speed_upper_mps``] (the replay observes the model through the same encoder: no residual while the model
  also stays short of the next edge).
* battery volts at every record (telemetry and burst samples).

The ESC pulse per tick: the bursts' 1 kHz samples where there are bursts; between telemetry records,
linear interpolation of the recorded pulse (``esc_pulse_fine_us``, the timer's 1/3 us, when the recording has
it) for a closed-loop run, or a zero-order hold when the pulse is held between records (an open-loop program).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler.recorder import read_recording
from robowrangler.recorder.burst import bursts as read_bursts
from robowrangler.recorder.errors import RecordingError
from robowrangler_sim.diagnose.encoder_pattern import corrected_counts, estimate_edge_pattern
from robowrangler_sim.diagnose.errors import DiagnoseError, MissingChannelsError, NoUsableSpanError

TICK_S = 1e-3
REQUIRED_FIELDS = ("time_s", "rope_speed_mps", "esc_pulse_us", "battery_v", "motor_rpm")
PREROLL_S = 0.3  # zero-throttle pulses prepended so the model's ESC arms as the device's had
MIN_DURATION_S = 2.0
MOVING_MPS = 0.3
MIN_ENCODER_INTERVALS = 50  # fewer intervals with new edges than this: use the filtered speed instead
REST_GAP_S = 0.02  # no edge for this long: the record observes a rope (nearly) at rest
HELD_PULSE_SHARE = 0.6  # records with an unchanged pulse while the rope moves, above this share: a held program

_LOW16_US = 65536  # a burst sample's edge time: the low 16 bits of the device's us clock

KIND_TELEMETRY = 0
KIND_BURST = 1


@dataclass(frozen=True)
class DriveData:
    """A recording's drive observations on the tick grid.

    Attributes:
        path: the recording.
        time_s: (S,) observation times, device clock, non-decreasing (telemetry and burst samples merged).
        kind: (S,) KIND_TELEMETRY or KIND_BURST per observation.
        sample_ticks: (S,) tick index of each observation in the replay's grid (pre-roll included).
        speed_mps: (S,) the rope speed observed (see ``speed_source``); rpm: (S,) the same as motor rpm;
        battery_v: (S,) battery volts.
        speed_valid: (S,) the record observes the speed (else speed_mps is 0 and carries no weight).
        speed_floor_mps: (S,) a known lower bound of the speed observation's sigma (less than one edge seen).
        edge_ticks: (S, 2) the interval [first, last] edge time, in fractional ticks, the speed is the mean over
            (speed_source "encoder"); NaN rows for "filtered".
        speed_upper_mps: (S,) for a record that saw no new edge for REST_GAP_S or more: the mean speed since the
            last edge is in [0, speed_upper_mps] (the distance to the next edge over the time since the last one;
            speed_mps is the midpoint); NaN for every other record.
        speed_source: "encoder" (mean speed between edge times) or "filtered" (telemetry rope_speed_mps).
        pulse_us: (T,) ESC pulse per 1 ms tick (pre-roll first).
        pulse_source: how pulse_us was made ("fine+bursts", "fine", "whole us", with "held"/"interpolated").
        tel_time_s, tel_speed_mps: the telemetry's own times and filtered rope speed (regimes, plots).
        state: (S_tel,) device state names. device_params: /device/params as floats.
        telemetry_hz: telemetry rate; bursts: number of 1 kHz bursts used; burst_s: seconds of burst samples.
        preroll_ticks: ticks before the first sample. truncated: the reader found the file cut short.
        notes: what this recording lacks for the diagnosis (coverage).
    """

    path: Path
    time_s: np.ndarray
    kind: np.ndarray
    sample_ticks: np.ndarray
    speed_mps: np.ndarray
    rpm: np.ndarray
    battery_v: np.ndarray
    speed_valid: np.ndarray
    speed_floor_mps: np.ndarray
    edge_ticks: np.ndarray
    speed_source: str
    pulse_us: np.ndarray
    pulse_source: str
    tel_time_s: np.ndarray
    tel_speed_mps: np.ndarray
    state: np.ndarray
    device_params: dict[str, float]
    telemetry_hz: float
    bursts: int
    burst_s: float
    preroll_ticks: int
    truncated: bool
    notes: list[str] = field(default_factory=list)
    speed_upper_mps: np.ndarray | None = None
    encoder_pattern: np.ndarray | None = None
    """The encoder's edge pattern calibrated on this recording (encoder_pattern.py; pitches per count mod
    counts_per_rev), None without 1 kHz bursts; the speeds are taken over the corrected edge positions."""

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def t_rel_s(self) -> np.ndarray:
        """Observation times from the first one, s."""
        return self.time_s - self.time_s[0]

    @property
    def tel(self) -> np.ndarray:
        """(S,) mask of the telemetry observations."""
        return self.kind == KIND_TELEMETRY


def _encoder_speed(time_s, counts, edge_s, group, step_m, next_pitch=None):
    """Mean speed over the edges counted since the group's previous record with a new edge.

    Returns (S,) speed, (S, 2) [first, last] edge times, (S,) sigma floor, (S,) upper bound. A record with no new
    edge whose last edge is REST_GAP_S old or more observes "less than one edge since": the rope's travel since
    that edge is in [0, next_pitch) pitches (next_pitch (S,): the distance from each record's latest edge to the
    next edge, in pitches; 1 when not given), so its mean speed over [last edge, record] is in [0, upper]; speed is
    the midpoint, with the uniform spread of that interval as its sigma floor. Other records without a new edge:
    NaN (upper NaN for every record that saw an edge).
    """
    n = time_s.size
    speed = np.full(n, np.nan)
    edges = np.full((n, 2), np.nan)
    floor = np.zeros(n)
    upper = np.full(n, np.nan)
    if next_pitch is None:
        next_pitch = np.ones(n)
    last: dict[int, int] = {}
    for i in range(n):
        g = int(group[i])
        if not (np.isfinite(counts[i]) and np.isfinite(edge_s[i])):
            continue
        j = last.get(g)
        if j is None:
            last[g] = i
            continue
        dn = counts[i] - counts[j]
        if dn <= 0:
            gap = time_s[i] - edge_s[j]
            if gap >= REST_GAP_S:
                upper[i] = next_pitch[j] * step_m / gap
                speed[i] = 0.5 * upper[i]
                edges[i] = (edge_s[j], time_s[i])
                floor[i] = upper[i] / np.sqrt(12.0)
            continue
        dt = edge_s[i] - edge_s[j]
        if dt > 0:
            speed[i] = dn * step_m / dt
            edges[i] = (edge_s[j], edge_s[i])
        last[g] = i
    return speed, edges, floor, upper


def _burst_count_offset(b_time_s: np.ndarray, b_counts: np.ndarray, tel_t: np.ndarray,
                        tel_counts: np.ndarray) -> float | None:
    """Edge index of a burst's count 0: telemetry count - burst count at the ticks both sampled (the most common
    difference), None when they share no tick or the telemetry has no counts."""
    if not np.all(np.isfinite(tel_counts)) or tel_t.size == 0:
        return None
    k = np.clip(np.searchsorted(tel_t, b_time_s), 0, tel_t.size - 1)
    k = np.where((k > 0) & (np.abs(tel_t[k - 1] - b_time_s) < np.abs(tel_t[k] - b_time_s)), k - 1, k)
    same = (np.abs(tel_t[k] - b_time_s) < 2.5e-4) & np.isfinite(b_counts)
    if not same.any():
        return None
    values, n = np.unique(np.round(tel_counts[k[same]] - b_counts[same]), return_counts=True)
    return float(values[np.argmax(n)])


def _unalias_burst_edges(b_counts: np.ndarray, b_edge_s: np.ndarray, tel_counts: np.ndarray,
                         tel_edge_s: np.ndarray) -> np.ndarray:
    """A burst sample carries its latest edge's time in 16 bits of us: an edge more than 65.536 ms old (a burst
    that starts with the rope at rest) reads as a recent one. A telemetry record with the same absolute count saw
    the same latest edge, with its 32-bit time: take that one where it differs by whole wraps."""
    ok = np.isfinite(tel_counts) & np.isfinite(tel_edge_s)
    if not ok.any():
        return b_edge_s
    tc, te = tel_counts[ok], tel_edge_s[ok]
    order = np.argsort(tc, kind="stable")
    tc, te = tc[order], te[order]
    k = np.clip(np.searchsorted(tc, b_counts), 0, tc.size - 1)
    same = np.isfinite(b_counts) & (tc[k] == b_counts)
    wraps = (b_edge_s - te[k]) / (_LOW16_US * 1e-6)
    fix = same & (np.round(wraps) >= 1) & (np.abs(wraps - np.round(wraps)) < 0.01)
    return np.where(fix, te[k], b_edge_s)


def load_drive_data(path: str | Path) -> DriveData:
    """Read and check a recording. Raises DiagnoseError (unreadable/corrupt), MissingChannelsError,
    NoUsableSpanError, each naming the file and what is missing."""
    path = Path(path)
    try:
        rec = read_recording(path)
    except RecordingError as err:
        raise DiagnoseError(f"{path}: not a readable recording: {err}") from err
    except OSError as err:
        raise DiagnoseError(f"{path}: cannot read: {err}") from err
    tel = rec.telemetry
    if not tel or "time_s" not in tel or len(tel["time_s"]) == 0:
        raise MissingChannelsError(f"{path}: no /device/telemetry messages (the diagnosis needs the drive "
                                   f"telemetry: {', '.join(REQUIRED_FIELDS)})")
    missing = [f for f in REQUIRED_FIELDS if f not in tel]
    if missing:
        raise MissingChannelsError(f"{path}: /device/telemetry lacks {', '.join(missing)}")
    t_all = np.asarray(tel["time_s"], dtype=float)
    cols = {f: np.asarray(tel[f], dtype=float) for f in REQUIRED_FIELDS}
    ok = np.all(np.isfinite(np.vstack(list(cols.values()))), axis=0)
    if ok.sum() < 10:
        raise MissingChannelsError(f"{path}: /device/telemetry has {int(ok.sum())} complete samples of "
                                   f"{', '.join(REQUIRED_FIELDS)}; at least 10 needed")
    # time order, duplicates (same time_s) keep the first
    idx = np.flatnonzero(ok)
    idx = idx[np.argsort(t_all[idx], kind="stable")]
    keep = np.concatenate(([True], np.diff(t_all[idx]) > 0.0))
    idx = idx[keep]
    sel = np.zeros(t_all.size, dtype=bool)
    sel[idx] = True
    tel_t = t_all[idx]
    tel_speed = cols["rope_speed_mps"][idx]
    states = np.asarray(tel.get("state", np.array(["UNKNOWN_0"] * t_all.size)), dtype=object)[idx]
    duration = tel_t[-1] - tel_t[0]
    if duration < MIN_DURATION_S:
        raise NoUsableSpanError(f"{path}: telemetry spans {duration:.2f} s; the diagnosis needs at least "
                                f"{MIN_DURATION_S} s with the rope moving")
    dt_tel = float(np.median(np.diff(tel_t)))
    moving = tel_speed > MOVING_MPS
    if moving.sum() * dt_tel < 1.0:
        raise NoUsableSpanError(f"{path}: the rope moves (> {MOVING_MPS} m/s) for less than 1 s of the "
                                f"{duration:.1f} s recorded: no span to compare the drive model on")
    if not np.any(cols["esc_pulse_us"][idx] > 0):
        raise NoUsableSpanError(f"{path}: esc_pulse_us is 0 throughout: no drive input to replay")
    params: dict[str, float] = {}
    for name, value in rec.metadata.get("/device/params", {}).items():
        try:
            params[name] = float(value)
        except ValueError:
            continue
    notes: list[str] = []
    telemetry_hz = 1.0 / dt_tel
    fine = "esc_pulse_fine_us" in tel and np.any(np.abs(np.asarray(tel["esc_pulse_fine_us"], float)[idx]
                                                        - np.round(np.asarray(tel["esc_pulse_fine_us"], float)[idx]))
                                                 > 1e-6)
    # telemetry records
    t_list = [tel_t]
    kind_list = [np.full(tel_t.size, KIND_TELEMETRY)]
    group_list = [np.zeros(tel_t.size)]
    pulse_src = np.asarray(tel["esc_pulse_fine_us"], float)[idx] if "esc_pulse_fine_us" in tel else cols["esc_pulse_us"][idx]
    pulse_list = [pulse_src]
    batt_list = [cols["battery_v"][idx]]
    if "encoder_counts" in tel and "encoder_edge_us" in tel:
        c = np.asarray(tel["encoder_counts"], float)[idx]
        e = np.asarray(tel["encoder_edge_us"], float)[idx]
        c = c[0] + np.concatenate(([0.0], np.cumsum(np.mod(np.diff(c), 2.0 ** 32))))
        age_us = np.mod(np.round(tel_t * 1e6) - e, 2.0 ** 32)
        counts_list = [c]
        edge_list = [tel_t - age_us * 1e-6]
    else:
        counts_list = [np.full(tel_t.size, np.nan)]
        edge_list = [np.full(tel_t.size, np.nan)]
    absolute_list = [np.isfinite(counts_list[0])]  # counts that are the device's edge index (edges since boot)
    n_bursts = 0
    burst_s = 0.0
    try:
        burst_list = read_bursts(rec)
    except (KeyError, TypeError, ValueError):
        burst_list = []
        notes.append("the /device/burst records could not be put together; bursts not used")
    for b in burst_list:
        present = np.isfinite(b.encoder_counts) & np.isfinite(b.esc_pulse_fine_us) & np.isfinite(b.battery_v)
        if present.sum() < 10:
            continue
        n_bursts += 1
        burst_s += float(present.sum()) * b.tick_s
        t_list.append(b.time_s[present])
        kind_list.append(np.full(int(present.sum()), KIND_BURST))
        group_list.append(np.full(int(present.sum()), float(n_bursts)))
        pulse_list.append(b.esc_pulse_fine_us[present])
        batt_list.append(b.battery_v[present])
        # a burst counts from its first sample: its samples at a telemetry record's tick give the offset to the
        # device's edge index (the same counter latched in the same tick)
        offset = _burst_count_offset(b.time_s[present], b.encoder_counts[present], tel_t, counts_list[0])
        counts_list.append(b.encoder_counts[present] + (offset if offset is not None else 0.0))
        absolute_list.append(np.full(int(present.sum()), offset is not None))
        edge_s_b = b.start_time_s + b.encoder_edge_s[present]
        if offset is not None:
            edge_s_b = _unalias_burst_edges(counts_list[-1], edge_s_b, counts_list[0], edge_list[0])
        edge_list.append(edge_s_b)
    time_s = np.concatenate(t_list)
    order = np.argsort(time_s, kind="stable")
    time_s = time_s[order]
    kind = np.concatenate(kind_list)[order].astype(np.int8)
    group = np.concatenate(group_list)[order]
    pulse_rec = np.concatenate(pulse_list)[order]
    battery = np.concatenate(batt_list)[order]
    counts = np.concatenate(counts_list)[order]
    edge_s = np.concatenate(edge_list)[order]
    absolute = np.concatenate(absolute_list)[order]
    # a burst sample at a telemetry record's time: both kept (different observations of one instant)
    r_m = params.get("wheel_radius_m", 0.015)
    cpr = params.get("encoder_counts_per_rev", 64.0)
    step_m = 2.0 * np.pi * r_m / cpr
    # the encoder's own edge pattern (encoder_pattern.py), calibrated on this recording: speeds over the
    # corrected edge positions
    pattern = estimate_edge_pattern(np.where(absolute, edge_s, np.nan), np.where(absolute, counts, np.nan), cpr)
    next_pitch = np.ones(time_s.size)
    if pattern is not None:
        ok = absolute & np.isfinite(counts)
        next_pitch[ok] = corrected_counts(counts[ok] + 1.0, pattern) - corrected_counts(counts[ok], pattern)
        counts = np.where(absolute, corrected_counts(counts, pattern), counts)
    enc_speed, enc_edges, enc_floor, enc_upper = _encoder_speed(time_s, counts, edge_s, group, step_m, next_pitch)
    t0 = float(tel_t[0])
    preroll = int(round(PREROLL_S / TICK_S))
    ticks_all = preroll + np.round((time_s - t0) / TICK_S).astype(np.int64)
    n_ticks = int(ticks_all.max()) + 1
    # pulse per tick
    tel_m = kind == KIND_TELEMETRY
    p_tel = pulse_rec[tel_m]
    mov = np.asarray(tel_speed > MOVING_MPS)
    same = np.abs(np.diff(p_tel)) < 1e-9
    held = bool(np.mean(same[mov[1:] & mov[:-1]]) > HELD_PULSE_SHARE) if np.any(mov[1:] & mov[:-1]) else True
    grid = np.arange(preroll, n_ticks)
    if held:
        k = np.searchsorted(ticks_all[tel_m], grid, side="right") - 1
        pulse_grid = p_tel[np.clip(k, 0, None)]
    else:
        pulse_grid = np.interp(grid, ticks_all[tel_m], p_tel)
    if n_bursts:
        bm = kind == KIND_BURST
        pulse_grid[ticks_all[bm] - preroll] = pulse_rec[bm]
    pulse = np.empty(n_ticks)
    first_pulse = p_tel[0]
    at_rest = tel_speed[0] < MOVING_MPS
    pulse[:preroll] = params.get("esc_min_us", 1000.0) if (at_rest and first_pulse > 0) else first_pulse
    pulse[preroll:] = pulse_grid
    pulse_source = ("fine (1/3 us)" if fine else "whole us") + (", held between records" if held else
                                                                ", interpolated between records")
    if n_bursts:
        pulse_source += f", 1 kHz in {n_bursts} burst(s)"
    # observations: every record (battery volts); its speed where the encoder gives one
    use_encoder = int(np.isfinite(enc_speed).sum()) >= MIN_ENCODER_INTERVALS
    if use_encoder:
        valid = np.isfinite(enc_speed)
        edges = (enc_edges - t0) / TICK_S + preroll
        valid &= (edges[:, 0] >= 0) & (edges[:, 1] <= n_ticks - 1)
        speed = np.where(valid, enc_speed, 0.0)
        edges[~valid] = np.column_stack([ticks_all, ticks_all + 1.0])[~valid].clip(max=n_ticks - 1)
        floor = np.where(valid, enc_floor, 0.0)
        upper = np.where(valid, enc_upper, np.nan)
        source = "encoder"
    else:
        valid = tel_m.copy()
        speed = np.where(valid, np.interp(time_s, tel_t, tel_speed), 0.0)
        edges = np.column_stack([ticks_all, ticks_all]).astype(float)
        floor = np.zeros(time_s.size)
        upper = np.full(time_s.size, np.nan)
        source = "filtered"
        notes.append("no encoder counts/edge times: compared on the filtered rope speed")
    if not n_bursts:
        notes.append("no 1 kHz bursts: latency, dead band and low-speed effects are judged from "
                      f"{telemetry_hz:.0f} Hz telemetry only (record with `wrangler excite --profile drive`)")
    if telemetry_hz < 90.0:
        notes.append(f"telemetry at {telemetry_hz:.0f} Hz (the firmware can send 100 Hz)")
    if not fine:
        notes.append("ESC pulse in whole us only (the firmware's esc_pulse_fine_us has 1/3 us)")
    r_wheel = r_m
    return DriveData(path=path, time_s=time_s, kind=kind, sample_ticks=ticks_all,
                     speed_mps=speed, rpm=speed / (2 * np.pi * r_wheel) * 60.0, battery_v=battery,
                     speed_valid=valid, speed_floor_mps=floor, speed_upper_mps=upper, edge_ticks=edges, speed_source=source, pulse_us=pulse, pulse_source=pulse_source,
                     tel_time_s=tel_t, tel_speed_mps=tel_speed, state=states, device_params=params,
                     telemetry_hz=telemetry_hz, bursts=n_bursts, burst_s=burst_s, preroll_ticks=preroll,
                     truncated=bool(rec.truncated), notes=notes, encoder_pattern=pattern)
