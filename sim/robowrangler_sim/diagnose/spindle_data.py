"""The spindle channels of one recording (guide position, spindle load, the spindle's command), on the 1 ms tick
grid the spindle replay runs on. Reads /device/telemetry only (never /sim/plant_truth).

Only samples from the first one whose spindle_flags has HOMED on are used (before homing the position counts from
power-up). A recording without these fields (older schema), or in which the spindle never moves, is not an error: the
drive can still be diagnosed. ``load_spindle_data`` then returns None and the reason, and the spindle effects
are reported as not testable in the coverage.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from robowrangler.recorder import read_recording
from robowrangler.recorder.errors import RecordingError

TICK_S = 1e-3
FIELDS = ("time_s", "guide_position_m", "spindle_load_permille", "spindle_moving_speed_raw")
MIN_TRAVEL_MM = 1.0
MIN_DRIVEN_S = 0.5
SLOW_RAW = 200  # commands up to this magnitude are "slow" (where a servo dead band shows)
REVERSAL_WINDOW_S = 0.6


@dataclass(frozen=True)
class SpindleData:
    """Spindle telemetry on the tick grid.

    time_s (S,) sample times; sample_ticks (S,) tick of each sample (0 = the first sample);
    moving_speed_raw (T,) the command in force per 1 ms tick (zero-order hold of the recorded one);
    guide_mm (S,) recorded guide position from home, mm; load_permille (S,) recorded present load (signed).
    """

    path: Path
    time_s: np.ndarray
    sample_ticks: np.ndarray
    moving_speed_raw: np.ndarray
    guide_mm: np.ndarray
    load_permille: np.ndarray

    @property
    def t_rel_s(self) -> np.ndarray:
        return self.time_s - self.time_s[0]

    @property
    def sample_raw(self) -> np.ndarray:
        """(S,) the command recorded with each sample."""
        return self.moving_speed_raw[np.minimum(self.sample_ticks, self.moving_speed_raw.size - 1)]


def load_spindle_data(path: str | Path) -> tuple[SpindleData | None, str]:
    """(data, "") or (None, why the spindle cannot be diagnosed from this recording)."""
    path = Path(path)
    try:
        tel = read_recording(path).telemetry
    except (RecordingError, OSError) as err:
        return None, f"not readable: {err}"
    missing = [f for f in FIELDS if f not in (tel or {})]
    if missing:
        return None, f"/device/telemetry lacks {', '.join(missing)}"
    cols = {f: np.asarray(tel[f], dtype=float) for f in FIELDS}
    ok = np.all(np.isfinite(np.vstack(list(cols.values()))), axis=0)
    if "spindle_flags" in tel:
        # the guide position means "from home" only once the spindle is homed (before, it counts from power-up
        # and homing jumps it to 0): diagnose from the first homed sample on
        homed = np.array(["HOMED" in (f if isinstance(f, (list, tuple, np.ndarray)) else str(f).split(","))
                          for f in tel["spindle_flags"]])
        if homed.any():
            ok &= np.arange(homed.size) >= int(np.argmax(homed))
    if ok.sum() < 20:
        return None, "fewer than 20 complete spindle samples"
    order = np.argsort(cols["time_s"][ok], kind="stable")
    cols = {f: v[ok][order] for f, v in cols.items()}
    keep = np.concatenate(([True], np.diff(cols["time_s"]) > 0.0))
    cols = {f: v[keep] for f, v in cols.items()}
    t = cols["time_s"]
    guide_mm = cols["guide_position_m"] * 1e3
    raw_s = cols["spindle_moving_speed_raw"].astype(np.int64)
    dt = float(np.median(np.diff(t)))
    driven_s = float(np.sum((raw_s & 0x3FF) > 0)) * dt
    if np.ptp(guide_mm) < MIN_TRAVEL_MM or driven_s < MIN_DRIVEN_S:
        return None, (f"the spindle hardly moves (guide travel {np.ptp(guide_mm):.2f} mm, driven {driven_s:.1f} s; "
                      f"needs >= {MIN_TRAVEL_MM} mm and >= {MIN_DRIVEN_S} s): run `wrangler excite --profile spindle`")
    ticks = np.round((t - t[0]) / TICK_S).astype(np.int64)
    idx = np.searchsorted(ticks, np.arange(int(ticks[-1]) + 1), side="right") - 1
    return SpindleData(path=path, time_s=t, sample_ticks=ticks, moving_speed_raw=raw_s[idx], guide_mm=guide_mm,
                       load_permille=cols["spindle_load_permille"]), ""


def spindle_regimes(data: SpindleData) -> dict[str, np.ndarray]:
    """Per sample: "spindle" in (retracting) / out (extending) / rest by the command; "reversal": within
    REVERSAL_WINDOW_S after the commanded direction flipped (rests in between do not reset it); "command":
    slow (0 < |command| <= SLOW_RAW) or fast or zero."""
    raw = data.sample_raw
    mag = raw & 0x3FF
    direction = np.where(mag == 0, 0, np.where(raw & 0x400, -1, 1))
    motion = np.where(direction > 0, "in", np.where(direction < 0, "out", "rest")).astype(object)
    rev = np.zeros(raw.size, dtype=bool)
    last = 0
    t_flip = -np.inf
    t = data.t_rel_s
    for i, d in enumerate(direction):
        if d != 0:
            if last != 0 and d != last:
                t_flip = t[i]
            last = d
        rev[i] = t[i] - t_flip <= REVERSAL_WINDOW_S
    command = np.where(mag == 0, "zero", np.where(mag <= SLOW_RAW, "slow", "fast")).astype(object)
    return {"spindle": motion, "reversal": np.where(rev, "yes", "no").astype(object), "command": command}


SPINDLE_REGIME_NAMES = {"spindle": ("in", "out", "rest"), "reversal": ("yes",), "command": ("slow", "fast")}


def spindle_coverage(labels: dict[str, np.ndarray] | None) -> dict[str, list[str]]:
    visited, missing = [], []
    for kind, names in SPINDLE_REGIME_NAMES.items():
        for name in names:
            hit = labels is not None and float(np.mean(labels[kind].astype(str) == name)) >= 0.01
            (visited if hit else missing).append(f"{kind}:{name}")
    return {"visited": visited, "not_visited": missing}
