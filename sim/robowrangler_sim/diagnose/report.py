"""Report: the plain first line, report.json (protocol/recording/diagnosis_report.md), PNGs and one
self-contained HTML page (figures inlined as base64)."""

from __future__ import annotations

import base64
import html
import json
import math
from pathlib import Path

import numpy as np

REPORT_FORMAT = "robowrangler.diagnosis"
REPORT_VERSION = 1


def _fmt_param(name: str, p: dict) -> str:
    """'name value unit (lo-hi)', the value and its interval in one unit: ms for a duration in seconds whose value
    and interval are all below 1 s, the parameter's own unit otherwise."""
    lo, hi = p["ci95"]
    unit, k, fmt = p["unit"], 1.0, ".3g"
    if unit == "s" and max(abs(p["value"]), abs(lo), abs(hi)) < 1.0:
        unit, k, fmt = "ms", 1e3, ".1f"
    return f"{name} {p['value'] * k:{fmt}} {unit} ({lo * k:{fmt}}-{hi * k:{fmt}})"


MISS_OVER_NOISE = 3.0
"""A held-out error beyond this many times the recorded noise is physics the model still lacks: with no effect of
the library to name it is not "none beyond noise", and after a named one the first line says how much is left."""


def first_line(result) -> str:
    """One line in plain words: what is left out (with its interval), where, and the held-out error."""
    if result.verdict == "none":
        held = result.candidates[0]["heldout_rms"]["rope_speed_mps"]
        noise = result.noise_rms.get("rope_speed_mps", float("nan"))
        if held > MISS_OVER_NOISE * noise:
            # where it misses most, when a span stands out of the residual (a miss spread over the run has none)
            worst = max(result.located, key=lambda d: d["significance"]) if result.located else None
            at = f" (most at {worst['span_s'][0]:.1f}-{worst['span_s'][1]:.1f} s)" if worst else " (spread over the run)"
            return (f"none of the library: no effect beats the refitted nominal model on held-out spans, yet it "
                    f"misses by {held * 1e3:.0f} mm/s against a noise of {noise * 1e3:.0f} mm/s{at}: physics outside "
                    "the library, or a nominal parameter beyond its bounds")
        return ("none beyond noise: the refitted nominal model explains the recording "
                f"(held-out speed error {held * 1e3:.0f} mm/s, noise {noise * 1e3:.0f} mm/s)")
    if result.verdict == "not_identifiable":
        d = result.not_identifiable[0]
        return f"not identifiable from these channels: {d['id']}; would separate them: {d['separating_measurement']}"
    parts = []
    for e in result.effects:
        ps = [_fmt_param(name, p) for name, p in e.params.items()]
        acts = f" ({e.regime['acts']})" if e.regime.get("acts") else ""
        parts.append(f"{e.effect_id.replace('_', ' ')}{acts} " + ", ".join(ps))
    e0 = result.effects[0]
    where = f"located in {len(e0.spans_s)} span(s)" if e0.spans_s else "spread over the recording"
    if "rope_speed_mps" not in e0.heldout_rms_before:  # a spindle effect: its own channels
        return (f"left out: {'; '.join(parts)}, {where}, held-out spindle load error "
                f"{e0.heldout_rms_before['spindle_load_permille']:.1f} -> "
                f"{e0.heldout_rms_after['spindle_load_permille']:.1f}"
                f" per mille, guide motion {e0.heldout_rms_before['guide_step_mm'] * 1e3:.1f} -> "
                f"{e0.heldout_rms_after['guide_step_mm'] * 1e3:.1f} um per 0.1 s")
    line = (f"left out: {'; '.join(parts)}, {where}, held-out error {_mmps(e0.heldout_rms_before)} -> "
            f"{_mmps(e0.heldout_rms_after)} mm/s")
    after = e0.heldout_rms_after["rope_speed_mps"]
    noise = result.noise_rms.get("rope_speed_mps", float("nan"))
    if after > MISS_OVER_NOISE * noise:
        line += (f", still {after * 1e3:.0f} mm/s against a noise of {noise * 1e3:.0f} mm/s: the closest law of the "
                 "library, not all of the physics")
    return line


def _mmps(rms: dict) -> str:
    return f"{rms['rope_speed_mps'] * 1e3:.0f}"


def _clean(x):
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(float(x)) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def report_json(result) -> dict:
    """The report.json document."""
    return _clean({
        "format": REPORT_FORMAT, "format_version": REPORT_VERSION, "recording": str(result.recording),
        "summary": first_line(result), "verdict": result.verdict,
        "effects": [{"id": e.effect_id, "law": e.law, "params": e.params, "channels": e.channels,
                     "spans_s": e.spans_s, "regime": e.regime, "heldout_rms_before": e.heldout_rms_before,
                     "heldout_rms_after": e.heldout_rms_after, "evidence": e.evidence} for e in result.effects],
        "not_identifiable": result.not_identifiable, "nominal_refit": result.nominal_refit,
        "unexplained_fraction": result.unexplained_fraction, "noise_rms": result.noise_rms,
        "coverage": result.coverage,
        "located": result.located, "candidates": result.candidates, "timings_s": result.timings_s,
        "spindle": getattr(result, "spindle", {}), "closed_loop": getattr(result, "closed_loop", None),
    })


def write_report(result, out_dir: str | Path) -> dict[str, Path]:
    """report.json, model.json, residual_map.png, overlay.png, spindle_overlay.png (when the spindle was diagnosed)
    and report.html in out_dir; returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"report": out / "report.json", "model": out / "model.json", "overlay": out / "overlay.png",
             "residual_map": out / "residual_map.png", "html": out / "report.html"}
    doc = report_json(result)
    paths["report"].write_text(json.dumps(doc, indent=1) + "\n")
    result.model.save(paths["model"])
    s = result.series
    t = s["time_s"]
    fig, ax = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    ax[0].plot(t, s["speed_mps"], "k.", ms=2, label="recording")
    ax[0].plot(t, s["refit_speed_mps"], label="nominal refit")
    ax[0].plot(t, s["after_speed_mps"], label="with the chosen effects")
    ax[0].set_ylabel("rope speed [m/s]")
    ax[0].legend(loc="upper right")
    ax[1].plot(t, s["battery_v"], "k.", ms=2)
    ax[1].plot(t, s["refit_battery_v"])
    ax[1].plot(t, s["after_battery_v"])
    ax[1].set_ylabel("battery [V]")
    ax[1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(paths["overlay"], dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(2, 1, figsize=(10, 5), sharex=True)
    r_before = s["speed_mps"] - s["refit_speed_mps"]
    r_after = s["speed_mps"] - s["after_speed_mps"]
    ax[0].plot(t, r_before * 1e3, label="nominal refit")
    ax[0].plot(t, r_after * 1e3, label="chosen model")
    for e in result.effects:
        for a, b in e.spans_s:
            ax[0].axvspan(a, b, color="tab:red", alpha=0.15)
    held = s["heldout"]
    ax[0].fill_between(t, ax[0].get_ylim()[0], ax[0].get_ylim()[1], where=held, color="0.85", alpha=0.5,
                       label="held out", step="mid")
    ax[0].set_ylabel("speed residual [mm/s]")
    ax[0].legend(loc="upper right")
    bands = sorted(set(s["speed_band"].astype(str)))
    codes = np.array([bands.index(b) for b in s["speed_band"].astype(str)])
    ax[1].scatter(t, codes, c=np.abs(r_before) * 1e3, s=6, cmap="viridis")
    ax[1].set_yticks(range(len(bands)), bands)
    ax[1].set_ylabel("speed band (colour: |residual|)")
    ax[1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(paths["residual_map"], dpi=90)
    plt.close(fig)
    figures = ["overlay", "residual_map"]
    if "spindle_time_s" in s:  # the spindle half: recorded guide motion and load, nominal refit and chosen model
        paths["spindle_overlay"] = out / "spindle_overlay.png"
        ts = s["spindle_time_s"]
        fig, ax = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
        ax[0].plot(ts, s["spindle_guide_mm"], "k.", ms=2, label="recording")
        ax[0].plot(ts, s["spindle_refit_guide_mm"], label="nominal refit (open loop)")
        ax[0].plot(ts, s["spindle_after_guide_mm"], label="with the chosen effects")
        ax[0].set_ylabel("guide [mm]")
        ax[0].legend(loc="upper right")
        ax[1].plot(ts, s["spindle_load_permille"], "k.", ms=2)
        ax[1].plot(ts, s["spindle_refit_load_permille"])
        ax[1].plot(ts, s["spindle_after_load_permille"])
        ax[1].set_ylabel("spindle load [per mille]")
        ax[2].plot(ts, s["spindle_load_permille"] - s["spindle_refit_load_permille"], label="nominal refit")
        ax[2].plot(ts, s["spindle_load_permille"] - s["spindle_after_load_permille"], label="chosen model")
        ax[2].set_ylabel("load residual")
        ax[2].set_xlabel("time [s]")
        ax[2].legend(loc="upper right")
        fig.tight_layout()
        fig.savefig(paths["spindle_overlay"], dpi=90)
        plt.close(fig)
        figures.append("spindle_overlay")
    imgs = "".join(f'<p><img alt="{k}" src="data:image/png;base64,'
                   f'{base64.b64encode(paths[k].read_bytes()).decode()}"></p>' for k in figures)
    rows = "".join(f"<tr><td>{html.escape(str(c['id']))}</td><td>{html.escape(str(c.get('status')))}</td>"
                   f"<td>{html.escape(json.dumps(_clean(c.get('heldout_rms', ''))))}</td></tr>" for c in result.candidates)
    cl = getattr(result, "closed_loop", None)
    cl_html = ""
    if cl:
        unit = {"rope_speed_mps": ("mm/s", 1e3), "guide_position_m": ("um", 1e6),
                "spindle_load_permille": ("per mille", 1.0)}
        cl_rows = "".join(f"<tr><td>{html.escape(ch)}</td><td>{v['nominal'] * unit[ch][1]:.1f}</td>"
                          f"<td>{v['fitted'] * unit[ch][1]:.1f}</td><td>{unit[ch][0]}</td></tr>"
                          for ch, v in cl["rms"].items() if ch in unit)
        cl_html = ("<h2>Closed loop: the SIL firmware on the recording's commands</h2><table border=1><tr><th>channel"
                   "</th><th>RMS, model as given</th><th>RMS, fitted model</th><th>unit</th></tr>" + cl_rows
                   + "</table>")
    paths["html"].write_text(
        "<!doctype html><html><head><meta charset='utf-8'><title>wrangler diagnose</title></head><body>"
        f"<h1>{html.escape(first_line(result))}</h1>{imgs}{cl_html}<h2>Candidates</h2><table border=1>"
        f"<tr><th>id</th><th>status</th><th>held-out RMS</th></tr>{rows}</table>"
        f"<h2>report.json</h2><pre>{html.escape(json.dumps(doc, indent=1))}</pre></body></html>\n")
    return paths
