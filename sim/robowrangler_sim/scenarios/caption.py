"""Captions on a scenario's rendered frames (`wrangler sil --scenario NAME --render DIR`), as the README's figure has.

Each frame gets a white band on top with one line: the simulated time, the firmware's state (from its telemetry),
the rope speed and the guide position (plant truth) and the script's phase::

    t 12.35 s | RETRACT | rope 0.00 m/s | guide 142.3 mm | grasp

The run's last frame is shown again with the verdict (``secured: follow 0.93, rope touching 92 %``), or with what
stopped the run (diverged, the firmware, interrupted). Drawn with OpenCV's Hershey font (no font files).
"""

from __future__ import annotations

import math

import numpy as np

BAND_PX = 26  # caption band height on a 360 px frame (scaled with the frame height)
TEXT_BGR = (20, 20, 20)
VERDICT_HOLD_S = 1.5  # the MP4 shows the verdict frame this long


def frame_caption(*, time_s: float, state: str | None, rope_speed_mps: float, guide_mm: float, phase: str) -> str:
    """The caption of one frame (units in the text)."""
    for name, value in (("time_s", time_s), ("rope_speed_mps", rope_speed_mps), ("guide_mm", guide_mm)):
        if not math.isfinite(value):
            raise ValueError(f"{name}: expected a finite number, got {value!r}")
    return (f"t {time_s:.2f} s | {state or '-'} | rope {rope_speed_mps:.2f} m/s | guide {guide_mm:.1f} mm | "
            f"{phase}")


def verdict_caption(outcome) -> str:
    """The last frame's caption: the verdict and the figures it rests on, or what ended the run without one."""
    if outcome.verdict in ("secured", "slipped"):
        return (f"{outcome.verdict}: follow {outcome.follow_ratio:.2f}, rope touching "
                f"{100 * outcome.touching_fraction:.0f} %")
    if outcome.verdict in ("held", "lost"):
        opened = ("" if outcome.door_opening_deg != outcome.door_opening_deg
                  else f", door opened {outcome.door_opening_deg:.1f} deg")
        return f"{outcome.verdict}: rope touching {100 * outcome.touching_fraction:.0f} %{opened}"
    if outcome.verdict == "interrupted":
        return "interrupted: no verdict"
    return f"no verdict: {outcome.verdict}"


def captioned(frame_rgb: np.ndarray, text: str) -> np.ndarray:
    """A copy of an (H, W, 3) uint8 RGB frame with ``text`` (one band line per line of text) in a white band
    over its top (same shape)."""
    import cv2

    if frame_rgb.ndim != 3 or frame_rgb.shape[2] != 3 or frame_rgb.dtype != np.uint8:
        raise ValueError(f"frame_rgb: expected an (H, W, 3) uint8 image, got {frame_rgb.shape} {frame_rgb.dtype}")
    out = np.ascontiguousarray(frame_rgb).copy()
    h, w = out.shape[:2]
    line_px = max(12, round(BAND_PX * h / 360))
    lines = text.splitlines() or [""]
    out[:min(h, line_px * len(lines))] = 255
    for i, line in enumerate(lines):
        scale = 0.5 * line_px / BAND_PX
        (text_w, _), _ = cv2.getTextSize(line, cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
        if text_w > w - 12:  # a long line shrinks to fit the frame's width
            scale *= (w - 12) / text_w
        cv2.putText(out, line, (6, round(line_px * (i + 0.72))), cv2.FONT_HERSHEY_SIMPLEX, scale, TEXT_BGR[::-1], 1,
                    cv2.LINE_AA)
    return out
