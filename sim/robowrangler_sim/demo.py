"""The end-to-end demo: SIL firmware + simulated drive, commanded by the real client over UDP.

Arm, spin the rope to 4 m/s, step to 6 m/s, spin down, disarm; then plot rope speed, setpoint, the ToV
line and the ESC pulse to a PNG. Everything goes through the same client and protocol as on the board.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from robowrangler.client import Client
from robowrangler.protocol.generated import PARAMS_BY_NAME, State
from robowrangler.telemetry import TelemetrySample
from robowrangler_sim.sil.metrics import settle_time_s
from robowrangler_sim.sil.session import SilSession

TOV_MPS = PARAMS_BY_NAME["tov_mps"].default
TOV_MARGIN = PARAMS_BY_NAME["tov_margin"].default


@dataclass(frozen=True)
class DemoResult:
    """What the demo measured. Times in seconds of device time."""

    plot_path: Path
    settle_4_mps_s: float | None
    settle_6_mps_s: float | None
    min_airborne_speed_mps: float
    samples: int
    wall_s: float


def _collect(client: Client, samples: list[TelemetrySample], stop: threading.Event) -> None:
    for sample in client.telemetry():
        samples.append(sample)
        if stop.is_set():
            return


def run_demo(out_png: str | Path, *, speedup: float = 1.0, seed: int = 0, hold_s: float = 2.5,
             progress: Callable[[str], None] = lambda _msg: None) -> DemoResult:
    """Run the demo and write the plot. progress(msg) is called at each step (for a live display)."""
    if not 0.1 <= speedup <= 3.0:
        raise ValueError(f"speedup: expected 0.1..3.0 (a demo to watch), got {speedup}")
    out_png = Path(out_png)
    wall0 = time.monotonic()
    samples: list[TelemetrySample] = []
    stop = threading.Event()
    progress("starting the SIL firmware and the simulated drive")
    with SilSession(speedup=speedup, seed=seed) as sil:
        sil.run_in_background()
        progress(f"SIL device listening on {sil.cmd_url}")
        with Client(sil.cmd_url, connect_timeout_s=5.0, key=sil.key) as rw:
            collector = threading.Thread(target=_collect, args=(rw, samples, stop), daemon=True)
            collector.start()
            progress("arm (waits out the ESC arming hold)")
            rw.arm(timeout_s=5.0)
            t_spin4 = rw.latest_telemetry.time_s
            progress("spin to 4 m/s")
            rw.spin(4.0)
            _sleep_device(rw, hold_s)
            t_spin6 = rw.latest_telemetry.time_s
            progress("step to 6 m/s")
            rw.spin(6.0)
            _sleep_device(rw, hold_s)
            t_down = rw.latest_telemetry.time_s
            progress("spin down")
            rw.spindown()
            rw.wait_for_state(State.ARMED, timeout_s=10.0)
            progress("disarm")
            rw.disarm()
            rw.wait_for_state(State.DISARMED, timeout_s=2.0)
            stop.set()
            events = rw.events
        sil.stop()
        sil.check()

    times = [s.time_s for s in samples]
    speeds = [s.rope_speed_mps for s in samples]

    settle4 = settle_time_s(times, speeds, target=4.0, start_s=t_spin4, end_s=t_spin6)
    settle6 = settle_time_s(times, speeds, target=6.0, start_s=t_spin6, end_s=t_down)
    airborne = [s.rope_speed_mps for s in samples if s.state == State.AIRBORNE]
    progress(f"plotting {len(samples)} telemetry samples to {out_png}")
    plot_demo(out_png, samples, events=[(e.time_s, f"{_name(e.state_from)}->{_name(e.state_to)}") for e in events
                                        if e.state_from != e.state_to])
    return DemoResult(plot_path=out_png, settle_4_mps_s=settle4, settle_6_mps_s=settle6,
                      min_airborne_speed_mps=min(airborne) if airborne else 0.0, samples=len(samples),
                      wall_s=time.monotonic() - wall0)


def _name(value: object) -> str:
    return getattr(value, "name", str(value))


def _sleep_device(client: Client, seconds: float) -> None:
    """Wait until the device clock has advanced by `seconds` (device time, not wall time)."""
    start = client.latest_telemetry.time_s
    for sample in client.telemetry():
        if sample.time_s - start >= seconds:
            return


def plot_demo(out_png: Path, samples: list[TelemetrySample], *, events: list[tuple[float, str]]) -> Path:
    """Rope speed, setpoint, target, ToV and guard lines (top) and ESC pulse (bottom) against device time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [s.time_s for s in samples]
    fig, (ax_v, ax_p) = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True, height_ratios=[2.2, 1])
    ax_v.plot(t, [s.rope_speed_mps for s in samples], color="tab:blue", lw=1.6, label="rope speed (measured)")
    ax_v.plot(t, [s.rope_speed_setpoint_mps for s in samples], color="tab:orange", lw=1.2, ls="--",
              label="setpoint (ramped)")
    ax_v.plot(t, [s.rope_speed_target_mps for s in samples], color="0.5", lw=0.8, ls=":", label="target")
    ax_v.axhline(TOV_MPS, color="tab:red", lw=1.0, label=f"ToV {TOV_MPS:g} m/s")
    ax_v.axhline(TOV_MPS * TOV_MARGIN, color="tab:red", lw=0.8, ls="--",
                 label=f"ToV guard x{TOV_MARGIN:g} = {TOV_MPS * TOV_MARGIN:.2f} m/s")
    for t_event, label in events:
        ax_v.axvline(t_event, color="0.85", lw=0.8, zorder=0)
        ax_v.text(t_event, 0.98, label, rotation=90, va="top", ha="right", fontsize=7, color="0.35",
                  transform=ax_v.get_xaxis_transform())
    ax_v.set_ylabel("rope speed [m/s]")
    ax_v.set_title("RoboWrangler SIL demo: rope speed loop (firmware core + simulated drive, over UDP)")
    ax_v.legend(loc="lower center", bbox_to_anchor=(0.5, 0.12), ncols=3, fontsize=8)
    ax_v.grid(alpha=0.3)
    ax_p.plot(t, [s.esc_pulse_us for s in samples], color="tab:green", lw=1.2, label="ESC pulse (both ESCs)")
    ax_p.set_ylabel("ESC pulse [us]")
    ax_p.set_xlabel("device time [s]")
    ax_p.legend(loc="upper left", fontsize=8)
    ax_p.grid(alpha=0.3)
    fig.tight_layout()
    out_png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
    return out_png
