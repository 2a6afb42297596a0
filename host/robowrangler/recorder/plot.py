"""Plot a recording to a PNG (matplotlib, Agg backend): `wrangler replay FILE --plot OUT.png`.

Panels against device time [s]: rope speed (measured, setpoint, target, ToV and ToV x margin), ESC pulse
[us], battery [V], state timeline with events. Telemetry gaps are shaded in every panel.
ToV and its margin come from the recording's "/device/params" metadata (read from the device at the
start of `wrangler record`), else the protocol's defaults (and the legend says so).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from robowrangler.protocol.generated import PARAMS_BY_NAME, State
from robowrangler.recorder.errors import RecordingError
from robowrangler.recorder.reader import Recording


def _tov(rec: Recording) -> tuple[float, float, str]:
    params = rec.metadata.get("/device/params", {})
    try:
        return float(params["tov_mps"]), float(params["tov_margin"]), "device"
    except (KeyError, ValueError):
        pass
    return PARAMS_BY_NAME["tov_mps"].default, PARAMS_BY_NAME["tov_margin"].default, "default"


def plot_recording(rec: Recording, out_png: str | Path, *, title: str | None = None) -> Path:
    """Write the PNG; returns its path. RecordingError if there is no telemetry to plot."""
    try:
        import matplotlib
    except ImportError as exc:
        raise RecordingError(rec.path, "plotting needs matplotlib, which this install lacks: add the extra "
                                       "`robowrangler[plot]` (or install robowrangler-sim, which has it)") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tele = rec.telemetry
    if len(tele["log_time_ns"]) == 0:
        raise RecordingError(rec.path, "nothing to plot: the recording has no /device/telemetry messages")
    t = tele["time_s"]
    tov, margin, origin = _tov(rec)
    fig, axes = plt.subplots(4, 1, sharex=True, figsize=(10, 9), height_ratios=[3, 2, 1.5, 2])
    ax = axes[0]
    ax.plot(t, tele["rope_speed_mps"], label="measured", lw=1.2)
    ax.plot(t, tele["rope_speed_setpoint_mps"], label="setpoint", lw=1.0)
    ax.plot(t, tele["rope_speed_target_mps"], label="target", lw=0.8, ls="--")
    ax.axhline(tov, color="k", lw=0.8, ls=":", label=f"ToV {tov:g} m/s ({origin})")
    ax.axhline(tov * margin, color="grey", lw=0.8, ls="-.", label=f"ToV x {margin:g}")
    ax.set_ylabel("rope speed [m/s]")
    ax.legend(loc="upper right", fontsize=8)
    axes[1].plot(t, tele["esc_pulse_us"], color="tab:red", lw=1.0)
    axes[1].set_ylabel("ESC pulse [us]")
    axes[2].plot(t, tele["battery_v"], color="tab:green", lw=1.0)
    axes[2].set_ylabel("battery [V]")
    names = [s.name for s in State]
    index = {n: i for i, n in enumerate(names)}
    codes = np.array([index.get(s, len(names)) for s in tele["state"]], dtype=float)
    axes[3].step(t, codes, where="post", color="tab:purple")
    axes[3].set_yticks(range(len(names)), names, fontsize=7)
    axes[3].set_ylabel("state")
    for ev in rec.events:
        axes[3].axvline(ev["time_s"], color="tab:orange", lw=0.6, alpha=0.7)
    for gap in rec.gaps:
        start = gap["last_time_s"] if gap["last_time_s"] is not None else t[0]
        end = gap["resume_time_s"] if gap["resume_time_s"] is not None else t[-1]
        for a in axes:
            a.axvspan(start, end, color="red", alpha=0.15, lw=0)
    axes[3].set_xlabel("device time [s]")
    for a in axes:
        a.grid(True, alpha=0.3)
    trunc = " (TRUNCATED)" if rec.truncated else ""
    fig.suptitle(title or f"{rec.path.name}: {rec.meta.get('source')} recording{trunc}", fontsize=10)
    fig.tight_layout()
    out = Path(out_png)
    try:
        fig.savefig(out, dpi=100)
    except OSError as err:
        raise RecordingError(out, f"cannot write the plot: {err.strerror or err}") from err
    finally:
        plt.close(fig)
    return out
