"""Typed errors of the chain model."""

from __future__ import annotations


class ChainModelError(ValueError):
    """A chain parameter, input or object spec is invalid; the message names argument, expected, actual."""


class ChainDivergenceError(RuntimeError):
    """The MuJoCo integration of the chain diverged (NaN, runaway velocity, or a solver reset).

    Attributes:
        time_s: simulated time at which divergence was detected.
        reason: short machine-readable cause ("nonfinite", "velocity", "badqacc", ...).
    """

    def __init__(self, *, time_s: float, reason: str, detail: str) -> None:
        super().__init__(f"chain simulation diverged at t={time_s:.4f} s ({reason}): {detail}")
        self.time_s = time_s
        self.reason = reason
