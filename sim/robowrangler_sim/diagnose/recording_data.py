"""The drive channels of one recording, checked and laid on the 1 ms tick grid the replay runs on.

Reads /device/telemetry only (never /sim/plant_truth: a board has none) and /device/params when present.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler.recorder import read_recording
from robowrangler.recorder.errors import RecordingError
from robowrangler_sim.diagnose.errors import DiagnoseError, MissingChannelsError, NoUsableSpanError

TICK_S = 1e-3
REQUIRED_FIELDS = ("time_s", "rope_speed_mps", "esc_pulse_us", "battery_v", "motor_rpm")
PREROLL_S = 0.3  # zero-throttle pulses prepended so the model's ESC arms as the device's had
MIN_DURATION_S = 2.0
MOVING_MPS = 0.3


@dataclass(frozen=True)
class DriveData:
    """Telemetry on the tick grid.

    Attributes:
        path: the recording.
        time_s: (S,) sample times, device clock.
        sample_ticks: (S,) tick index of each sample in the replay's grid (pre-roll included).
        pulse_us: (T,) ESC pulse per 1 ms tick (zero-order hold of the recorded pulse, pre-roll first).
        speed_mps: (S,) measured rope speed; rpm: (S,) motor rpm; battery_v: (S,) battery voltage.
        state: (S,) device state names.
        device_params: /device/params as floats (empty if the recording has none).
        preroll_ticks: ticks before the first sample.
        truncated: the reader found the file cut short (read up to the cut).
    """

    path: Path
    time_s: np.ndarray
    sample_ticks: np.ndarray
    pulse_us: np.ndarray
    speed_mps: np.ndarray
    rpm: np.ndarray
    battery_v: np.ndarray
    state: np.ndarray
    device_params: dict[str, float]
    preroll_ticks: int
    truncated: bool

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def t_rel_s(self) -> np.ndarray:
        """Sample times from the first sample, s."""
        return self.time_s - self.time_s[0]


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
    t = np.asarray(tel["time_s"], dtype=float)
    cols = {f: np.asarray(tel[f], dtype=float) for f in REQUIRED_FIELDS}
    ok = np.all(np.isfinite(np.vstack(list(cols.values()))), axis=0)
    if ok.sum() < 10:
        raise MissingChannelsError(f"{path}: /device/telemetry has {int(ok.sum())} complete samples of "
                                   f"{', '.join(REQUIRED_FIELDS)}; at least 10 needed")
    order = np.argsort(t[ok], kind="stable")
    t = t[ok][order]
    cols = {f: v[ok][order] for f, v in cols.items()}
    keep = np.concatenate(([True], np.diff(t) > 0.0))  # duplicates (same time_s) keep the first
    t = t[keep]
    cols = {f: v[keep] for f, v in cols.items()}
    states = np.asarray(tel.get("state", np.array(["UNKNOWN_0"] * len(ok))), dtype=object)[ok][order][keep]
    duration = t[-1] - t[0]
    if duration < MIN_DURATION_S:
        raise NoUsableSpanError(f"{path}: telemetry spans {duration:.2f} s; the diagnosis needs at least "
                                f"{MIN_DURATION_S} s with the rope moving")
    moving = cols["rope_speed_mps"] > MOVING_MPS
    if moving.sum() * np.median(np.diff(t)) < 1.0:
        raise NoUsableSpanError(f"{path}: the rope moves (> {MOVING_MPS} m/s) for less than 1 s of the "
                                f"{duration:.1f} s recorded: no span to compare the drive model on")
    if not np.any(cols["esc_pulse_us"] > 0):
        raise NoUsableSpanError(f"{path}: esc_pulse_us is 0 throughout: no drive input to replay")
    params: dict[str, float] = {}
    for name, value in rec.metadata.get("/device/params", {}).items():
        try:
            params[name] = float(value)
        except ValueError:
            continue
    preroll = int(round(PREROLL_S / TICK_S))
    ticks = preroll + np.round((t - t[0]) / TICK_S).astype(np.int64)
    n_ticks = int(ticks[-1]) + 1
    pulse = np.empty(n_ticks)
    first_pulse = cols["esc_pulse_us"][0]
    at_rest = cols["rope_speed_mps"][0] < MOVING_MPS
    pulse[:preroll] = params.get("esc_min_us", 1000.0) if (at_rest and first_pulse > 0) else first_pulse
    idx = np.searchsorted(ticks, np.arange(preroll, n_ticks), side="right") - 1
    pulse[preroll:] = cols["esc_pulse_us"][idx]
    return DriveData(path=path, time_s=t, sample_ticks=ticks, pulse_us=pulse, speed_mps=cols["rope_speed_mps"],
                     rpm=cols["motor_rpm"], battery_v=cols["battery_v"], state=states, device_params=params,
                     preroll_ticks=preroll, truncated=bool(rec.truncated))
