"""Flutter of the observed loop: how unevenly the contour scatters from frame to frame along the loop, and the error a
shorter, fluttering loop is refused with (LoopFlutterError).

The camera's noise scatters every contour point alike. A rope that folds and flutters on part of the loop scatters
those points much more: per point, the frame-to-frame scatter of its normal offset (noise_sigma: second differences,
so the loop's own smooth motion at 30 Hz drops out); the loop flutters when the 90th percentile of the points is at
least FLUTTER_UNEVENNESS x their lower quartile. On the string shooter's dev recordings (bench/bench_diagnose_loop.py
seeds 1-3, all cases, and `--only headwind`, winds on seeds 11-18): 1.2-1.4 on steady loops (the camera's 2 or 4 mm,
fast turns included), 1.85 on C_f x 1.25 at 5 m/s (a loop that flutters 5-7 mm), 2.0 on a 0.5 m/s head wind at
5 m/s (named right; the report notes the flutter), 2.2-4.8 on every head wind whose contour is more than 10 % short.

What such a loop is (the string shooter, head wind w < 0 along the launch heading): the outgoing branch meets the air
at v + |w|, its skin friction rises by (1 + |w| / v)^2 and the nip's push must carry it; the rope there goes into
material compression (T = T_e + lambda v^2 at the exit: -2.2 mN in still air at 5 m/s, -3.3 to -3.8 mN at w = -0.5 to
-1.8 m/s, with 52-53 % of the rope's segments compressed from -0.8 m/s against 15 % in still air), buckles and folds
in a few centimetres, below the contour's 5 cm point spacing; the folded stretch is shorter on the contour, the
loop's reach halves (0.94 -> 0.49 m at w = -1.83 m/s, 0.78 -> 0.45 m at 4 m/s, w = -1.48 m/s) and the contour
flutters 10-50 mm. The library's laws are steady shapes about the table's (uniform_wind: the first-order response of
a rope in tension, with the end point and the end tangents held and the exit's reaction free, which barely moves the
reach: 0.93-0.94 m for w = 0 to -5 m/s at 5 m/s and phi 0.1 rad; a continuation that carries the applied wind load
into each step's balance reaches 0.88 m in 16 steps, against the truth's 0.45 m), so they leave it out; a light head
wind is named (0.5 m/s at 5 m/s: -0.504 m/s, with C_f 13 % low beside it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robowrangler_sim.diagnose.errors import ModelMismatchError
from robowrangler_sim.diagnose.residuals import noise_sigma

FLUTTER_UNEVENNESS = 2.0
"""The loop flutters when the 90th percentile of the points' frame-to-frame scatter is at least this x their lower
quartile (steady loops: 1.2-1.4; see the module doc)."""


class LoopFlutterError(ModelMismatchError):
    """The observed loop is shorter than the model's and flutters unevenly along its contour: the rope folds on part
    of the loop, which no steady law of the library represents (the message gives the measurements)."""


@dataclass(frozen=True)
class ContourScatter:
    """Frame-to-frame scatter of the contour points' normal offsets (metres, 1 sigma per point).

    Attributes: per_point_m (K - 2,) interior points; lower_quartile_m, p90_m its 25th and 90th percentiles;
    worst_fraction: arc fraction (0 exit, 1 return) of the point that scatters most."""

    per_point_m: np.ndarray
    lower_quartile_m: float
    p90_m: float
    worst_fraction: float

    @property
    def unevenness(self) -> float:
        return self.p90_m / max(self.lower_quartile_m, 1e-12)

    @property
    def flutters(self) -> bool:
        return bool(self.unevenness >= FLUTTER_UNEVENNESS)

    def report(self) -> dict:
        """report.json's loop.flutter: the two percentiles (mm), their ratio, the threshold, whether it flutters."""
        return {"p90_mm": round(self.p90_m * 1e3, 3), "lower_quartile_mm": round(self.lower_quartile_m * 1e3, 3),
                "unevenness": round(self.unevenness, 3), "threshold": FLUTTER_UNEVENNESS, "flutters": self.flutters}


def contour_scatter(points_m: np.ndarray, normals: np.ndarray, segment: np.ndarray) -> ContourScatter:
    """Scatter of contours points_m (F, K, 2) along normals (F, K, 2), per point the median over the airborne
    stretches (segment (F,)) of at least 5 frames of noise_sigma of its normal offset."""
    proj = np.sum(np.asarray(points_m) * np.asarray(normals), axis=-1)
    segs = [np.flatnonzero(segment == s) for s in np.unique(segment)]
    segs = [m for m in segs if m.size >= 5]
    k_pts = proj.shape[1]
    if not segs or k_pts < 3:
        nan = float("nan")
        return ContourScatter(np.full(max(k_pts - 2, 0), nan), nan, nan, nan)
    per = np.array([np.median([noise_sigma(proj[m, k]) for m in segs]) for k in range(1, k_pts - 1)])
    q25, q90 = np.percentile(per, [25.0, 90.0])
    worst = (int(np.argmax(per)) + 1) / (k_pts - 1)
    return ContourScatter(per, float(q25), float(q90), float(worst))


def flutter_note(scatter: ContourScatter) -> str:
    """The report's note (and first-line tail) for a loop that flutters but is not refused."""
    return (f"the contour flutters unevenly from frame to frame ({scatter.p90_m * 1e3:.1f} mm at the 90th percentile "
            f"of the points, {scatter.lower_quartile_m * 1e3:.1f} mm at their lower quartile): the rope folds on part "
            "of the loop (a head wind does this), which the library's steady laws leave out")


def flutter_message(scatter: ContourScatter, *, reach_observed_m: float, reach_model_m: float) -> str:
    """What a shorter, fluttering loop is and what the library leaves out (follows the length figures)."""
    where = ("near the exit" if scatter.worst_fraction < 0.1 or scatter.worst_fraction > 0.9 else
             "on the outgoing (upper) branch or the tip" if scatter.worst_fraction < 0.55 else
             "on the returning (lower) branch")
    return (f"; the loop reaches {reach_observed_m:.2f} m where the model's reaches {reach_model_m:.2f} m, and its "
            f"contour flutters unevenly from frame to frame ({scatter.p90_m * 1e3:.1f} mm at the 90th percentile of "
            f"the points, {scatter.lower_quartile_m * 1e3:.1f} mm at their lower quartile, most {where}; a camera's "
            "noise scatters all points alike): the rope folds and flutters there, so the contour is shorter than the "
            "rope. The library's laws are steady shapes about the table's (uniform_wind: the response of a rope in "
            "tension), so this loop is outside them and nothing is named. A head wind does this (its extra skin "
            "friction puts the outgoing branch in compression, which buckles it: from about 0.8 m/s against a "
            "4-6 m/s rope); record in still air, or measure the wind")
