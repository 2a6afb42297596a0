"""Candidate effects: the base class every effect of the library implements (one file per effect).

A candidate is a physical law with named parameters (units, bounds), the channels and regime where it shows,
and the measurement that would separate it from what it can be mistaken for. It maps its parameters onto the
batched drive plant's theta columns (robowrangler_sim.plants.drive_batch), so the fitter can simulate a batch
of its parameter sets at once. An effect the recorded channels cannot show says so in ``identifiable`` (it is
then reported as not identifiable, with the measurement that would show it) instead of being fitted.

Issue 15's rope-loop contours plug in here: a loop candidate subclasses Candidate with its own ``plant``
("loop") and theta mapping; the fitter and selector only use this interface.
"""

from __future__ import annotations

from abc import ABC
from dataclasses import dataclass, replace

import numpy as np

from robowrangler_sim.diagnose.parameters import ParamSpec


@dataclass(frozen=True)
class Identifiability:
    """Whether a recording can show an effect; if not, why and which measurement would."""

    identifiable: bool
    reason: str = ""
    separating_measurement: str = ""


class Candidate(ABC):
    """One effect of the library.

    Class attributes: effect_id (stable id used in reports), law (the law in words, for the report), plant
    ("drive" or "spindle"), channels (telemetry fields where it shows), regime (where it shows, in words),
    params (free ParamSpecs; a spec with a nominal parameter's column replaces that one), neutral (theta
    column -> value with the effect off), separating_measurement (what would tell it from its look-alikes),
    confused_with (effect ids or nominal parameters it can be mistaken for).
    """

    effect_id: str = ""
    law: str = ""
    plant: str = "drive"
    channels: tuple[str, ...] = ("rope_speed_mps",)
    regime: str = ""
    params: tuple[ParamSpec, ...] = ()
    neutral: dict[int, float] = {}
    separating_measurement: str = ""
    confused_with: tuple[str, ...] = ()
    uses_located_spans: bool = False
    gateable: bool = False
    """Whether the law may act in one regime only (gates.py): the diagnosis then also fits it confined to the
    regimes where the residual concentrates."""
    gated_floor: tuple[str, ...] = ()
    """Parameters (the effect's size) that, confined to a regime, may not fall below their value outside it nor
    below what the nominal model allows as a unit property: an effect there is more of it (a delay of 0 above
    5 m/s with the ESC's own delay below is not a latency, nor is an ESC delay that varies within its 0-3 ms)."""

    def gated_params(self, off_row: np.ndarray, unit_top: dict[int, float]) -> tuple[ParamSpec, ...]:
        """This law's parameters for a fit confined to a regime: the gated_floor ones bounded below by off_row and
        by unit_top (theta column -> the nominal refit's upper bound there, for the columns it refits)."""
        out = []
        for s in self.params:
            if s.name in self.gated_floor:
                lo = max(s.lo, float(off_row[s.column]), unit_top.get(s.column, s.lo))
                s = replace(s, lo=min(lo, s.hi))
            out.append(s)
        return tuple(out)
    needs_regimes: tuple[str, ...] = ()
    """Regime labels (regimes.py, "kind:label") of which the recording must visit at least one for the effect to
    show; a recording that visits none cannot test it (reported under coverage)."""

    def identifiable(self, data) -> Identifiability:
        """Can this recording show the effect at all? Default: yes."""
        return Identifiability(True)

    def start_points(self, theta: np.ndarray) -> np.ndarray:
        """Starting values (G, P) of this candidate's parameters for a batched grid search; default: the
        bounds' geometric/arithmetic midpoints and a few spreads."""
        rows = []
        for frac in (0.1, 0.3, 0.6):
            rows.append([s.bounds(theta[s.column])[0] + frac * (s.bounds(theta[s.column])[1]
                                                                 - s.bounds(theta[s.column])[0])
                         for s in self.params])
        return np.asarray(rows)

    def start_grid(self, theta: np.ndarray) -> tuple[list[int], np.ndarray]:
        """(theta columns, (G, len(columns)) values) of the batched start search; default: this candidate's
        own parameters at start_points. A candidate whose look-alike is a nominal parameter searches both."""
        return [s.column for s in self.params], self.start_points(theta)

    project_starts: bool = False
    """Whether the start grid's rows are judged with the other free parameters re-adjusted to each (ModelFitter's
    project_starts): for a law whose grid places it in time, where the refit has absorbed part of it elsewhere."""

    def untested_reason(self, values: dict[str, float], *, heldout_gap_s: float) -> str | None:
        """Why this law's fitted values cannot have been tested on held-out samples (values: the fit's parameter
        name -> value; heldout_gap_s: the longest stretch of fit samples between held-out blocks), or None.
        Default: None (a law that acts wherever its regime recurs)."""
        return None

    def starts_in_gate(self, grid: np.ndarray, mask_on: np.ndarray) -> np.ndarray:
        """The rows of start_grid worth trying when the law is confined to the ticks mask_on; default: all."""
        return grid

    def apply_neutral(self, theta: np.ndarray) -> np.ndarray:
        out = theta.copy()
        for col, value in self.neutral.items():
            out[..., col] = value
        return out

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"
