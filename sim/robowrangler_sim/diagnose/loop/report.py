"""The loop diagnosis' report: plain first line, its report.json section, PNGs (contour error over time before and
after; observed vs model contours at the worst frame) and an HTML page."""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np

from robowrangler_sim.diagnose.report import _clean


LEFT_OVER_NOISE = 2.0
"""A held-out contour error beyond this many times the camera noise is physics the model still lacks: with no
effect named the first line says "none of the loop candidates explains it", after a named one "still ... mm"."""


def loop_first_line(res) -> str:
    base = res.candidates[0]["heldout_rms_mm"]
    if res.verdict == "none" and base > LEFT_OVER_NOISE * res.noise_mm:
        where = f" (largest on the {res.located['part'].replace('_', ' ')})" if res.located.get("part") else ""
        return (f"loop: none of the loop candidates explains it, but the contours differ from the refitted chain by "
                f"{base:.1f} mm held out against {res.noise_mm:.1f} mm camera noise{where}: physics outside the library")
    if res.verdict == "none":
        held = [r["id"] for r in res.candidates if r["status"] == "within_noise"]
        within = (f"; {', '.join(i.replace('_', ' ') for i in held)} would lower it a little, but nothing beyond "
                  "the noise is left to explain" if held else "")
        return (f"loop: none beyond noise: the refitted chain explains the contours (held-out contour error "
                f"{base:.2f} mm, camera noise {res.noise_mm:.2f} mm{within})")
    if res.verdict == "not_identifiable":
        d = res.not_identifiable[0]
        return f"loop: not identifiable from these contours: {d['id']}; would separate them: {d['separating_measurement']}"
    e = res.effects[0]
    named = " together with ".join(
        f"{x.effect_id.replace('_', ' ')} " + ", ".join(f"{k} {p['value']:.3g} {p['unit']} ({p['ci95'][0]:.3g}-"
                                                          f"{p['ci95'][1]:.3g})" for k, p in x.params.items())
        for x in res.effects)
    line = (f"loop: left out: {named}, mostly on the {e.part.replace('_', ' ')}, held-out contour error "
            f"{e.heldout_rms_mm_before:.1f} -> {e.heldout_rms_mm_after:.1f} mm")
    if e.heldout_rms_mm_after > LEFT_OVER_NOISE * res.noise_mm:
        line += (f", still {e.heldout_rms_mm_after:.1f} mm against {res.noise_mm:.1f} mm camera noise: the closest "
                 "law of the library, not all of the physics")
        flutter = getattr(res, "flutter", None) or {}  # LoopDiagnosis.flutter (ContourScatter.report)
        if flutter.get("flutters"):
            line += (f"; the contour flutters unevenly ({flutter['p90_mm']:.1f} against "
                     f"{flutter['lower_quartile_mm']:.1f} mm): the rope folds on part of the loop, which the "
                     "steady laws leave out")
    return line


def loop_report_json(res) -> dict:
    return _clean({
        "recording": str(res.recording), "summary": loop_first_line(res), "verdict": res.verdict,
        "effects": [{"id": e.effect_id, "law": e.law, "params": e.params, "part": e.part, "spans_s": e.spans_s,
                     "heldout_rms_mm_before": e.heldout_rms_mm_before, "heldout_rms_mm_after": e.heldout_rms_mm_after,
                     "evidence": e.evidence} for e in res.effects],
        "not_identifiable": res.not_identifiable, "nominal_refit": res.nominal_refit, "noise_mm": res.noise_mm,
        "beyond_noise": bool(res.candidates[0]["heldout_rms_mm"] > LEFT_OVER_NOISE * res.noise_mm),
        "heldout_excess_z": res.candidates[0]["heldout_excess_z"],
        "frames": res.frames, "located": res.located, "candidates": res.candidates, "notes": res.notes,
        "flutter": res.flutter, "timings_s": res.timings_s,
    })


def write_loop_report(res, out_dir: str | Path) -> dict[str, Path]:
    """loop_report.json, loop_model.json, loop_error.png, loop_contours.png, loop_report.html in out_dir."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"report": out / "loop_report.json", "model": out / "loop_model.json", "error": out / "loop_error.png",
             "contours": out / "loop_contours.png", "html": out / "loop_report.html"}
    doc = loop_report_json(res)
    paths["report"].write_text(json.dumps(doc, indent=1) + "\n")
    res.model.save(paths["model"])
    s = res.series
    t = s["time_s"]
    fig, ax = plt.subplots(figsize=(10, 3.5))
    ax.plot(t, s["rms_before_mm"], ".", ms=3, label="chain (own parameters refitted)")
    ax.plot(t, s["rms_after_mm"], ".", ms=3, label="with the chosen effect")
    ax.axhline(res.noise_mm, color="0.5", ls="--", label="camera noise")
    for sp in res.located["spans_s"]:
        ax.axvspan(sp[0], sp[1], color="tab:red", alpha=0.1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("contour error RMS [mm]")
    ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(paths["error"], dpi=90)
    plt.close(fig)
    replay = s["replay"]
    f = int(np.argmax(s["rms_before_mm"]))
    before = replay.contours(s["nominal_theta"][None, :])[0, f]
    after = replay.contours(s["after_theta"][None, :])[0, f]
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot(*s["observed"][f].T, "k.", label="camera")
    ax.plot(*before.T, label="chain")
    ax.plot(*after.T, label="chain + effect")
    ax.set_aspect("equal")
    ax.set_title(f"t = {t[f]:.2f} s (largest error)")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(paths["contours"], dpi=90)
    plt.close(fig)
    imgs = "".join(f'<p><img alt="{k}" src="data:image/png;base64,{base64.b64encode(paths[k].read_bytes()).decode()}">'
                   "</p>" for k in ("error", "contours"))
    paths["html"].write_text(
        "<!doctype html><html><head><meta charset='utf-8'><title>wrangler diagnose: loop</title></head><body>"
        f"<h1>{html.escape(loop_first_line(res))}</h1>{imgs}<h2>report</h2>"
        f"<pre>{html.escape(json.dumps(doc, indent=1))}</pre></body></html>\n")
    return paths
