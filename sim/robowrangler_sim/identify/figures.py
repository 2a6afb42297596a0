"""Figures: one PNG per photo (the photo, the extracted centre line, the fitted chain), and the accuracy
plot per phi in the manner of the paper's Fig. 5a."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from robowrangler_sim.identify.extract import PhotoResult
from robowrangler_sim.shape_table import ShapeTable

MAX_FIGURE_WIDTH_PX = 1600


def write_photo_figure(result: PhotoResult, table: ShapeTable, path: str | Path, *, n_links: int = 20) -> Path:
    """The photo cropped round the loop, with the extracted centre line (green), the table's contour at
    this photo's phi (red) and a chain of ``n_links`` equal links laid on it (yellow dots), exit (blue)."""
    from robowrangler_sim.identify.photos import read_gray
    from robowrangler_sim.shape_table import resample_by_arc_length

    gray = read_gray(result.entry.path)
    img = cv2.cvtColor(gray, cv2.COLOR_GRAY2BGR)
    model = table.contour(result.entry.phi_deg, rope_speed_mps=result.entry.rope_speed_mps)
    scale = result.loop_length_m / float(np.sum(np.linalg.norm(np.diff(model, axis=0), axis=1)))
    chain = resample_by_arc_length(model * scale, n_links + 1)
    model_px = result.table_to_image(model)
    chain_px = result.table_to_image(chain)
    every = np.vstack([result.centre_line_px, model_px, [result.entry.exit_px]])
    pad = 60
    u0, v0 = np.maximum(np.floor(every.min(axis=0)).astype(int) - pad, 0)
    u1, v1 = np.ceil(every.max(axis=0)).astype(int) + pad
    crop = img[v0:v1, u0:u1].copy()
    off = np.array([u0, v0], float)
    shift = 4

    def fx(p):
        return np.round((p - off) * (1 << shift)).astype(np.int32)

    cv2.polylines(crop, [fx(result.centre_line_px)], False, (0, 220, 0), 2, cv2.LINE_AA, shift)
    cv2.polylines(crop, [fx(model_px)], False, (40, 40, 255), 1, cv2.LINE_AA, shift)
    for p in fx(chain_px):
        cv2.circle(crop, tuple(int(c) for c in p), 4 << shift, (0, 230, 255), 1, cv2.LINE_AA, shift)
    cv2.circle(crop, tuple(int(c) for c in fx(np.array([result.entry.exit_px]))[0]), 6 << shift, (255, 120, 0), 2,
               cv2.LINE_AA, shift)
    label = (f"{result.entry.path.name}: phi {result.entry.phi_deg:+g} deg, {result.entry.rope_speed_mps:g} m/s, "
             f"loop {result.loop_length_m:.3f} m | green: centre line, red: table, yellow: {n_links}-link chain")
    if crop.shape[1] > MAX_FIGURE_WIDTH_PX:
        f = MAX_FIGURE_WIDTH_PX / crop.shape[1]
        crop = cv2.resize(crop, None, fx=f, fy=f, interpolation=cv2.INTER_AREA)
    canvas = np.full((crop.shape[0] + 28, crop.shape[1], 3), 255, np.uint8)
    canvas[28:] = crop
    cv2.putText(canvas, label, (6, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    path = Path(path)
    if not cv2.imwrite(str(path), canvas):
        raise OSError(f"{path}: could not write the figure")
    return path


def plot_accuracy_per_phi(rows: list[dict], path: str | Path, *, loop_length_m: float, title: str) -> Path:
    """The paper's Fig. 5a measure per phi: max and mean distance from the true centre line to the model's
    curve, for each method in ``rows`` ({method, phi_deg, max_m, mean_m, held_out}), with the paper's 2 %
    and our 1 % target. Held-out angles are drawn hollow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    methods = sorted({r["method"] for r in rows})
    colours = dict(zip(methods, ("tab:blue", "tab:orange", "tab:green", "tab:red")))
    for m in methods:
        rs = sorted((r for r in rows if r["method"] == m), key=lambda r: r["phi_deg"])
        phi = np.array([r["phi_deg"] for r in rs])
        mx = np.array([100 * r["max_m"] for r in rs])
        mn = np.array([100 * r["mean_m"] for r in rs])
        held = np.array([bool(r["held_out"]) for r in rs])
        c = colours[m]
        ax.plot(phi, mx, "-", color=c, lw=1.2, label=f"{m}: max")
        ax.plot(phi, mn, ":", color=c, lw=1.2, label=f"{m}: mean")
        ax.plot(phi[~held], mx[~held], "o", color=c, ms=5)
        ax.plot(phi[held], mx[held], "o", mfc="white", color=c, ms=5)
    ax.axhline(2.0 * loop_length_m, color="gray", ls="--", lw=1, label="paper: max 2 % of loop")
    ax.axhline(1.0 * loop_length_m, color="black", ls="-.", lw=1, label="target: 1 % of loop")
    ax.set_xlabel("phi (deg)  (hollow: held-out angles, not photographed for the table)")
    ax.set_ylabel("distance true centre line -> model (cm)")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
