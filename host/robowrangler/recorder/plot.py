"""Plot a recording to a PNG (matplotlib, Agg backend): `wrangler replay FILE --plot OUT.png`.

Panels against device time [s]: rope speed (measured, setpoint, target, ToV and ToV x margin), ESC pulse
[us], guide position and target [mm] with the soft limits, spindle load [%] with the grasp's secure load,
battery [V], state timeline. Events are vertical lines and telemetry gaps shaded bands in every panel, both
in the legend. from_s/to_s limit the plot to a window of device time.
ToV, its margin, the guide limits and the secure load come from the recording's "/device/params" metadata
(read from the device at the start of `wrangler record`), else the protocol's defaults (the legend says so).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robowrangler.protocol.generated import PARAMS_BY_NAME, State
from robowrangler.recorder.errors import RecordingError
from robowrangler.recorder.reader import Recording


def _param(rec: Recording, name: str) -> tuple[float, str]:
    """A device parameter from the recording's /device/params, else the protocol default; and which it is."""
    try:
        return float(rec.metadata.get("/device/params", {})[name]), "device"
    except (KeyError, ValueError):
        return PARAMS_BY_NAME[name].default, "default"


def plot_recording(rec: Recording, out_png: str | Path, *, title: str | None = None, from_s: float | None = None,
                   to_s: float | None = None) -> Path:
    """Write the PNG; returns its path. RecordingError if there is no telemetry to plot (in the window)."""
    try:
        import matplotlib
    except ImportError as exc:
        raise RecordingError(rec.path, "plotting needs matplotlib, which this install lacks: add the extra "
                                       "`robowrangler[plot]` (or install robowrangler-sim, which has it)") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    tele = rec.telemetry
    if len(tele["log_time_ns"]) == 0:
        raise RecordingError(rec.path, "nothing to plot: the recording has no /device/telemetry messages")
    t_all = tele["time_s"]
    keep = np.ones(len(t_all), dtype=bool)
    if from_s is not None:
        keep &= t_all >= from_s
    if to_s is not None:
        keep &= t_all <= to_s
    if not keep.any():
        raise RecordingError(rec.path, f"nothing to plot between {'-' if from_s is None else f'{from_s:g}'} and "
                             f"{'-' if to_s is None else f'{to_s:g}'} s of device time: the telemetry spans "
                             f"{t_all[0]:.3f}..{t_all[-1]:.3f} s")
    t = t_all[keep]
    lo, hi = float(t[0]), float(t[-1])

    def col(name: str) -> np.ndarray:  # a field an outside writer left out is a blank line, not an error
        return tele[name][keep] if name in tele else np.full(len(t), np.nan)

    tov, origin = _param(rec, "tov_mps")
    margin, _ = _param(rec, "tov_margin")
    fig, axes = plt.subplots(6, 1, sharex=True, figsize=(10, 12), height_ratios=[3, 1.5, 2, 1.5, 1, 2])
    ax = axes[0]
    ax.plot(t, col("rope_speed_mps"), label="measured", lw=1.2)
    ax.plot(t, col("rope_speed_setpoint_mps"), label="setpoint", lw=1.0)
    ax.plot(t, col("rope_speed_target_mps"), label="target", lw=0.8, ls="--")
    ax.axhline(tov, color="k", lw=0.8, ls=":", label=f"ToV {tov:g} m/s ({origin})")
    ax.axhline(tov * margin, color="grey", lw=0.8, ls="-.", label=f"ToV x {margin:g} (guard)")
    ax.set_ylabel("rope speed [m/s]")
    axes[1].plot(t, col("esc_pulse_us"), color="tab:red", lw=1.0)
    axes[1].set_ylabel("ESC pulse [us]")
    guide_min, g_origin = _param(rec, "guide_min_mm")
    guide_max, _ = _param(rec, "guide_max_mm")
    axes[2].plot(t, col("guide_position_m") * 1000.0, color="tab:brown", lw=1.2, label="guide")
    axes[2].plot(t, col("guide_target_m") * 1000.0, color="tab:brown", lw=0.8, ls="--", label="target")
    for limit in (guide_min, guide_max):
        axes[2].axhline(limit, color="grey", lw=0.6, ls=":")
    axes[2].set_ylabel("guide [mm]")
    axes[2].legend(loc="upper right", fontsize=7, title=f"limits {guide_min:g}..{guide_max:g} mm ({g_origin})",
                   title_fontsize=7)
    secure, s_origin = _param(rec, "grasp_secure_load_pct")
    axes[3].plot(t, col("spindle_load_permille") / 10.0, color="tab:olive", lw=1.0, label="spindle load")
    axes[3].axhline(secure, color="grey", lw=0.8, ls="-.", label=f"secure {secure:g} % ({s_origin})")
    axes[3].set_ylabel("load [%]")
    axes[3].legend(loc="upper right", fontsize=7)
    axes[4].plot(t, col("battery_v"), color="tab:green", lw=1.0)
    axes[4].set_ylabel("battery [V]")
    names = [s.name for s in State]
    index = {n: i for i, n in enumerate(names)}
    codes = np.array([index.get(s, len(names)) for s in col("state")], dtype=float)
    axes[5].step(t, codes, where="post", color="tab:purple")
    axes[5].set_yticks(range(len(names)), names, fontsize=7)
    axes[5].set_ylabel("state")
    events = [ev for ev in rec.events if lo <= ev["time_s"] <= hi]
    for ev in events:
        for a in axes:
            a.axvline(ev["time_s"], color="tab:orange", lw=0.6, alpha=0.7)
    gaps = 0
    for gap in rec.gaps:
        start = gap["last_time_s"] if gap["last_time_s"] is not None else lo
        end = gap["resume_time_s"] if gap["resume_time_s"] is not None else hi
        if end < lo or start > hi:
            continue
        gaps += 1
        for a in axes:
            a.axvspan(max(start, lo), min(end, hi), color="red", alpha=0.15, lw=0)
    handles, labels = ax.get_legend_handles_labels()
    handles += [Line2D([], [], color="tab:orange", lw=0.8), Patch(color="red", alpha=0.15)]
    labels += [f"event ({len(events)})", f"telemetry gap ({gaps})"]
    ax.legend(handles, labels, loc="upper right", fontsize=8, ncols=2)
    axes[5].set_xlabel("device time [s]")
    if hi > lo:
        axes[5].set_xlim(lo, hi)
    for a in axes:
        a.grid(True, alpha=0.3)
    trunc = " (TRUNCATED)" if rec.truncated else ""
    window = "" if from_s is None and to_s is None else f", {lo:.2f}..{hi:.2f} s"
    fig.suptitle(title or f"{rec.path.name}: {rec.meta.get('source')} recording{trunc}{window}", fontsize=10)
    fig.tight_layout()
    out = Path(out_png)
    try:
        fig.savefig(out, dpi=100)
    except OSError as err:
        raise RecordingError(out, f"cannot write the plot: {err.strerror or err}") from err
    finally:
        plt.close(fig)
    return out
