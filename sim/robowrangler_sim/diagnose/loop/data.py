"""The loop channels of one recording: camera contours (/loop/observation) with the rope speed, the guide
position and the module's inclination at each frame, checked against the shape table's frame.

Rope speed per frame: /device/telemetry rope_speed_mps interpolated to the frame time, else the observation's own
rope_speed_mps. Guide position: /device/telemetry guide_position_m, else the guide at home (0 m, noted).
Only frames where the chain model flies the loop are compared: rope speed at least AIRBORNE_MARGIN x ToV, and
TAKEOFF_SETTLE_S after the speed last crossed it (the takeoff itself is the lift model's business, not the
shape table's).

Loop length: a contour longer than the model's loop by more than LOOP_LENGTH_TOLERANCE is refused here (no loop
effect lengthens the rope). A shorter one, down to SHORT_LOOP_FLOOR, is what a rope that flutters or folds at the tip
looks like on a K-point contour (a head wind crumples the tip: the resampled contour is shorter than the rope); the
loader keeps it (LoopData.length_ratio) and the diagnosis refuses it only when no loop effect explains the contours.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robowrangler.recorder import read_recording
from robowrangler.recorder.errors import RecordingError
from robowrangler_sim.diagnose.errors import DiagnoseError, MissingChannelsError, ModelMismatchError, NoUsableSpanError
from robowrangler_sim.shape_table import resample_by_arc_length

N_POINTS = 40
MIN_POINTS = 8
MIN_FRAMES = 30
AIRBORNE_MARGIN = 1.1
TAKEOFF_SETTLE_S = 1.0
LOOP_LENGTH_TOLERANCE = 0.10
SHORT_LOOP_FLOOR = 0.70
EXIT_TOLERANCE_FRACTION = 0.05


class ContourFrameError(DiagnoseError):
    """The contours are not in the shape table's frame (origin at the exit, x out, z up, metres)."""


@dataclass(frozen=True)
class LoopData:
    """Airborne camera frames of one recording, ready for the loop replay.

    Attributes:
        path: the recording.
        time_s: (F,) frame times; phi_rad: (F,) inclination; speed_mps: (F,) rope speed; guide_m: (F,) guide travel.
        points_m: (F, K, 2) observed contour resampled to K points equally spaced in arc length.
        segment: (F,) index of the contiguous airborne stretch each frame belongs to.
        observed_length_m: (F,) arc length of each observed contour.
        notes: what the loader assumed (missing optional channels).
        length_ratio: median observed / model loop length; outside 1 +- LOOP_LENGTH_TOLERANCE only when shorter and
            deferred (see module doc): the diagnosis then needs an effect that explains the contours.
    """

    path: Path
    time_s: np.ndarray
    phi_rad: np.ndarray
    speed_mps: np.ndarray
    guide_m: np.ndarray
    points_m: np.ndarray
    segment: np.ndarray
    observed_length_m: np.ndarray
    frames_total: int
    notes: list[str] = field(default_factory=list)
    length_ratio: float = 1.0

    @property
    def n_frames(self) -> int:
        return int(self.time_s.size)

    @property
    def n_points(self) -> int:
        return int(self.points_m.shape[1])

    @property
    def duration_s(self) -> float:
        return float(self.time_s[-1] - self.time_s[0]) if self.time_s.size else 0.0


def has_loop_observations(path: str | Path) -> bool:
    """True when the recording holds at least one /loop/observation record."""
    try:
        rec = read_recording(Path(path))
    except (RecordingError, OSError):
        return False
    return bool(rec.records.get("/loop/observation"))


def _arc_length(points: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


def load_loop_data(path: str | Path, *, takeoff_speed_mps: float, loop_length_of_guide, n_points: int = N_POINTS,
                   defer_short_loop: bool = False) -> LoopData:
    """Read and check the loop channels. loop_length_of_guide: guide travel (m) -> the model's loop length (m).
    defer_short_loop: keep a loop shorter than the model's (down to SHORT_LOOP_FLOOR) for the diagnosis to explain
    (LoopData.length_ratio) instead of raising ModelMismatchError here.

    Raises MissingChannelsError (no /loop/observation, no phi, no rope speed), ContourFrameError (contours not in
    the table's frame), NoUsableSpanError (too few points or airborne frames), ModelMismatchError (the observed
    loop is not as long as the model's), each naming the file, what was expected and what was found."""
    path = Path(path)
    try:
        rec = read_recording(path)
    except RecordingError as err:
        raise DiagnoseError(f"{path}: not a readable recording: {err}") from err
    except OSError as err:
        raise DiagnoseError(f"{path}: cannot read: {err}") from err
    rows = [r.data for r in rec.records.get("/loop/observation", [])]
    if not rows:
        raise MissingChannelsError(f"{path}: no /loop/observation messages (the loop diagnosis needs camera contours)")
    no_phi = sum(1 for r in rows if r.get("phi_rad") is None)
    if no_phi:
        raise MissingChannelsError(f"{path}: /loop/observation: {no_phi} of {len(rows)} frames have no phi_rad "
                                   "(the shape table is indexed by the module's inclination)")
    counts = np.array([len(r.get("points_m") or []) for r in rows])
    if np.median(counts) < MIN_POINTS:
        raise NoUsableSpanError(f"{path}: /loop/observation: contours have {int(np.median(counts))} points "
                                f"(median); at least {MIN_POINTS} needed to compare a loop shape")
    rows = [r for r, c in zip(rows, counts) if c >= MIN_POINTS]
    rows.sort(key=lambda r: float(r["time_s"]))
    t = np.array([float(r["time_s"]) for r in rows])
    phi = np.array([float(r["phi_rad"]) for r in rows])
    notes: list[str] = []
    tel = rec.telemetry
    if tel and "time_s" in tel and "rope_speed_mps" in tel and len(tel["time_s"]) >= 2:
        tt = np.asarray(tel["time_s"], dtype=float)
        order = np.argsort(tt)
        speed = np.interp(t, tt[order], np.asarray(tel["rope_speed_mps"], dtype=float)[order])
        if "guide_position_m" in tel:
            guide = np.interp(t, tt[order], np.asarray(tel["guide_position_m"], dtype=float)[order])
        else:
            guide = np.zeros_like(t)
            notes.append("no guide_position_m in /device/telemetry: guide taken at home (0 m)")
    else:
        sp = [r.get("rope_speed_mps") for r in rows]
        if any(s is None for s in sp):
            raise MissingChannelsError(f"{path}: no rope speed: neither /device/telemetry rope_speed_mps nor "
                                       "/loop/observation rope_speed_mps on every frame")
        speed = np.array(sp, dtype=float)
        guide = np.zeros_like(t)
        notes.append("rope speed from /loop/observation (no telemetry); guide taken at home (0 m)")
    # airborne frames: above ToV x margin, and settled after the last crossing
    fast = speed >= AIRBORNE_MARGIN * takeoff_speed_mps
    last_cross = -np.inf
    keep = np.zeros(t.size, dtype=bool)
    seg = np.zeros(t.size, dtype=int)
    k_seg = -1
    for i in range(t.size):
        if not fast[i]:
            last_cross = np.inf
            continue
        if last_cross == np.inf or i == 0 or not fast[i - 1]:
            last_cross = t[i]
            k_seg += 1
        if t[i] - last_cross >= TAKEOFF_SETTLE_S:
            keep[i] = True
            seg[i] = k_seg
    if keep.sum() < MIN_FRAMES:
        raise NoUsableSpanError(f"{path}: {int(keep.sum())} airborne camera frames (rope at least "
                                f"{AIRBORNE_MARGIN:g} x ToV = {AIRBORNE_MARGIN * takeoff_speed_mps:.2f} m/s for "
                                f"{TAKEOFF_SETTLE_S:g} s); at least {MIN_FRAMES} needed")
    idx = np.flatnonzero(keep)
    pts = np.empty((idx.size, n_points, 2))
    lengths = np.empty(idx.size)
    for j, i in enumerate(idx):
        raw = np.asarray(rows[i]["points_m"], dtype=float)
        if raw.ndim != 2 or raw.shape[1] != 2 or not np.all(np.isfinite(raw)):
            raise ContourFrameError(f"{path}: /loop/observation at t = {t[i]:.3f} s: points_m is not a list of "
                                    f"finite [x_m, z_m] pairs (shape {raw.shape})")
        lengths[j] = _arc_length(raw)
        if lengths[j] <= 0:
            raise ContourFrameError(f"{path}: /loop/observation at t = {t[i]:.3f} s: contour of zero length")
        pts[j] = resample_by_arc_length(raw, n_points)
    # segments renumbered 0..
    _, seg_k = np.unique(seg[idx], return_inverse=True)
    data = LoopData(path=path, time_s=t[idx], phi_rad=phi[idx], speed_mps=speed[idx], guide_m=guide[idx],
                    points_m=pts, segment=seg_k, observed_length_m=lengths, frames_total=len(rows), notes=notes)
    ratio = _check_frame(data, loop_length_of_guide)
    if abs(ratio - 1.0) > LOOP_LENGTH_TOLERANCE:
        if not (defer_short_loop and SHORT_LOOP_FLOOR <= ratio < 1.0):
            raise ModelMismatchError(length_mismatch_message(data, loop_length_of_guide, ratio))
        notes.append(f"the observed loop is {1.0 - ratio:.0%} shorter than the model's (ratio {ratio:.3f}): kept for "
                     "a loop effect to explain (a rope fluttering or folding at the tip is shorter on the contour)")
    return dataclasses.replace(data, length_ratio=ratio)


def length_mismatch_message(data: LoopData, loop_length_of_guide, ratio: float, *, calibration: bool = True) -> str:
    """What a loop-length mismatch says: observed and model lengths, the ratio, the tolerance; with calibration, the
    reading (another rope length or guide calibration) and what to pass."""
    model_len = np.array([loop_length_of_guide(g) for g in data.guide_m])
    figures = (f"{data.path}: the observed loop is {np.median(data.observed_length_m):.3f} m long (median), the "
               f"model's {np.median(model_len):.3f} m at the recorded guide position (ratio {ratio:.3f}, tolerance "
               f"+-{LOOP_LENGTH_TOLERANCE:.0%})")
    if not calibration:
        return figures
    return figures + ": another rope length or guide calibration; pass a chain model with the right rope_length_m"


def _check_frame(data: LoopData, loop_length_of_guide) -> float:
    """The table's frame: metres, the exit at the origin, the upper branch above the lower one, and a loop as long
    as the model's."""
    model_len = np.array([loop_length_of_guide(g) for g in data.guide_m])
    ratio = float(np.median(data.observed_length_m / model_len))
    exit_dist = np.linalg.norm(data.points_m[:, 0, :], axis=1)
    tol = EXIT_TOLERANCE_FRACTION * float(np.median(model_len))
    if ratio > 20 or ratio < 0.05:
        raise ContourFrameError(f"{data.path}: contours are {ratio:.3g} x the model's loop length "
                                f"({np.median(model_len):.2f} m): expected metres in the shape table's frame "
                                "(pixels or millimetres?)")
    if np.median(exit_dist) > tol:
        raise ContourFrameError(f"{data.path}: contours start {np.median(exit_dist):.3f} m from the origin (median); "
                                f"expected the exit point at (0, 0) within {tol:.3f} m (shape table frame: origin at "
                                "the guide exit)")
    k3 = data.n_points // 3
    upper_z = data.points_m[:, 1:k3, 1].mean(axis=1)
    lower_z = data.points_m[:, -k3:-1, 1].mean(axis=1)
    if np.median(upper_z - lower_z) < 0:
        raise ContourFrameError(f"{data.path}: the first third of the contours lies below the last third (median "
                                f"{np.median(upper_z - lower_z):.3f} m): expected z up and the contour running out "
                                "along the upper branch first (mirrored or reversed contours?)")
    if np.median(data.points_m[:, :, 0].max(axis=1)) <= 0:
        raise ContourFrameError(f"{data.path}: contours do not reach out in +x: expected x pointing away from the "
                                "robot")
    return ratio
