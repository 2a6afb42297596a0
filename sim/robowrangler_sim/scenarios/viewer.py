"""Watching a scenario live: MuJoCo's interactive passive viewer, synced with the chain while the firmware runs.

``run_scenario(name, viewer=True)`` (``wrangler sil --scenario NAME --viewer``) opens
``mujoco.viewer.launch_passive`` on the scenario's chain model and data; after every chain step the
scenario calls ``ScenarioViewer.sync(time_s)``, which pushes the state to the window and paces the run so
that simulated time goes by at ``speedup`` x wall time (the SIL is lockstep and unpaced otherwise: nothing
in the outcome depends on the pacing). Closing the window lets the run go on unpaced to its verdict.

The viewer needs an interactive OpenGL context (GLFW) on a display: on Linux DISPLAY (X11) or
WAYLAND_DISPLAY must be set, and MUJOCO_GL must be unset or "glfw" (MUJOCO_GL=osmesa/egl are headless
backends: they draw offscreen frames, --render, and cannot open a window). ``viewer_unavailable_reason``
checks this before anything opens a window; ViewerUnavailable carries the reason.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Mapping

HEADLESS_GL = ("osmesa", "egl")


class ViewerUnavailable(RuntimeError):
    """No interactive viewer here; the message names the environment variables to set (MUJOCO_GL, DISPLAY)."""


def viewer_unavailable_reason(environ: Mapping[str, str], *, platform: str | None = None) -> str | None:
    """Why the interactive viewer cannot open with these environment variables, or None if it can try.

    Args:
        environ: environment variables (os.environ or the CLI's injected mapping).
        platform: sys.platform (None: this process's); only Linux/BSD need DISPLAY or WAYLAND_DISPLAY.
    """
    platform = sys.platform if platform is None else platform
    gl = environ.get("MUJOCO_GL", "")
    if gl.lower() in HEADLESS_GL:
        return (f"the interactive viewer needs MUJOCO_GL unset or 'glfw', got MUJOCO_GL={gl!r} (a headless "
                "backend: use --render DIR for PNG/MP4 frames instead)")
    if platform.startswith(("linux", "freebsd", "openbsd")) and not (environ.get("DISPLAY")
                                                                      or environ.get("WAYLAND_DISPLAY")):
        return ("the interactive viewer needs a display: DISPLAY (X11) or WAYLAND_DISPLAY is unset here, and "
                "MUJOCO_GL unset or 'glfw' (headless: use --render DIR with MUJOCO_GL=osmesa for PNG/MP4 frames "
                "instead)")
    return None


class ScenarioViewer:
    """A passive MuJoCo viewer on a chain plant, paced to wall time.

    Args:
        model, data: the chain's MjModel and MjData (ChainPlant.model / .data).
        speedup: simulated seconds per wall second while the window is open (> 0).
        launch: opens the window, ``launch(model, data) -> handle`` with handle.sync(), .is_running(),
            .close(); default mujoco.viewer.launch_passive.
        clock_s: wall clock in seconds (default time.perf_counter); sleep_s: sleeps that long.
    """

    def __init__(self, model, data, *, speedup: float = 1.0, launch: Callable | None = None,
                 clock_s: Callable[[], float] = time.perf_counter,
                 sleep_s: Callable[[float], None] = time.sleep) -> None:
        if not (isinstance(speedup, (int, float)) and math.isfinite(speedup) and speedup > 0):
            raise ValueError(f"speedup: expected a finite factor > 0, got {speedup!r}")
        if launch is None:
            import mujoco.viewer

            launch = mujoco.viewer.launch_passive
        self.speedup = float(speedup)
        self._clock_s = clock_s
        self._sleep_s = sleep_s
        self._handle = launch(model, data)
        self._origin: tuple[float, float] | None = None
        self.syncs = 0

    @property
    def open(self) -> bool:
        """True while the window is open (the user has not closed it)."""
        return self._handle is not None and bool(self._handle.is_running())

    def sync(self, time_s: float) -> None:
        """Show the state at simulated time time_s; sleep so that it appears at speedup x wall time."""
        if not self.open:
            return
        now = self._clock_s()
        if self._origin is None:
            self._origin = (now, time_s)
        wall0, sim0 = self._origin
        ahead_s = (time_s - sim0) / self.speedup - (now - wall0)
        if ahead_s > 0:
            self._sleep_s(ahead_s)
        elif ahead_s < -0.5:  # the machine fell behind: do not race to catch up
            self._origin = (now, time_s)
        self._handle.sync()
        self.syncs += 1

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None
