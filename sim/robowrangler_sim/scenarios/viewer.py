"""MuJoCo's interactive viewer on a firmware-driven scenario (``wrangler sil --scenario NAME --viewer``).

The passive viewer (``mujoco.viewer.launch_passive``) shows the scenario's rope chain while the SIL runs it:
the scenario's thread steps the firmware, the plants and the chain exactly as without a viewer, and
ScenarioViewer, called once per control tick (run_scenario's ``watch``), hands the chain's MuJoCo state to
the viewer (``sync``) at most ``sync_hz`` times per simulated second and paces the run to ``speedup``
simulated seconds per wall second, so that a person can follow it (a scenario is otherwise unpaced).
Closing the window ends the drawing and the pacing; the run goes on to its verdict, unchanged: the viewer
only reads the simulation, so the outcome is the same with or without it.

The viewer opens an OpenGL window through GLFW: it needs a display (``DISPLAY`` for X11, or
``WAYLAND_DISPLAY``) and MuJoCo's GL backend left at GLFW (``MUJOCO_GL`` unset or ``glfw`` when mujoco is
first imported; ``osmesa`` and ``egl``, which headless rendering (--render) uses, have no windows).
display_problem() says what is missing before anything is run.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Mapping

from robowrangler_sim.scenarios.wall_pacer import WallPacer

HEADLESS_HINT = "on a machine without a display, record the run instead: --render DIR (MUJOCO_GL=osmesa)"


class ViewerUnavailable(RuntimeError):
    """MuJoCo's interactive viewer cannot open here; the message names MUJOCO_GL / DISPLAY and what to do."""


def display_problem(environ: Mapping[str, str]) -> str | None:
    """Why the interactive viewer cannot open with these environment variables, or None if it can try.

    Args:
        environ: the process environment (``os.environ`` or the CLI's injected one).
    """
    gl = environ.get("MUJOCO_GL", "")
    if gl and gl.lower() != "glfw":
        return (f"the interactive viewer needs MuJoCo's GLFW backend and a display, but MUJOCO_GL={gl!r} is a "
                f"headless backend: unset MUJOCO_GL (or set MUJOCO_GL=glfw) and run where DISPLAY (X11) or "
                f"WAYLAND_DISPLAY is set; {HEADLESS_HINT}")
    if not environ.get("DISPLAY") and not environ.get("WAYLAND_DISPLAY"):
        return ("the interactive viewer needs a display: neither DISPLAY (X11) nor WAYLAND_DISPLAY is set "
                f"(MUJOCO_GL={gl or 'unset'}; the viewer uses MUJOCO_GL=glfw); {HEADLESS_HINT}")
    return None


def glfw_problem() -> str | None:
    """Why GLFW cannot open a window here (it cannot reach the display), or None. MuJoCo's viewer initialises
    GLFW in its own thread and, when that fails, MuJoCo's fatal-error handler ends the whole process with no
    word to the caller; so the CLI asks first, in its own thread, and says what is missing."""
    import warnings

    import glfw

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ok = glfw.init()
    if ok:
        glfw.terminate()  # the viewer's thread initialises GLFW again for itself
        return None
    detail = "; ".join(str(w.message) for w in caught) or "glfw.init() failed"
    return f"GLFW could not reach the display ({detail})"


def _launch_passive(model, data):
    import mujoco.viewer

    problem = glfw_problem()
    if problem is not None:
        raise ViewerUnavailable(f"the interactive viewer cannot open a window: {problem}; check DISPLAY / "
                                f"WAYLAND_DISPLAY (MUJOCO_GL=glfw); {HEADLESS_HINT}")
    return mujoco.viewer.launch_passive(model, data)


class ScenarioViewer:
    """Draws a ChainPlant in MuJoCo's passive viewer while a scenario steps it; paces the run.

    Args:
        speedup: simulated seconds per wall second while the window is open (1 = real time); None = unpaced.
        sync_hz: viewer updates per simulated second (at most one per call).
        launch: ``launch(model, data) -> handle`` with ``sync()``, ``is_running()``, ``close()``, ``lock()`` and
            ``cam`` (default: mujoco.viewer.launch_passive).
        clock_s, sleep_s: wall clock and sleep (seconds), injectable for determinism of the pacing.

    Call it with the chain plant once per control tick (``run_scenario(..., watch=viewer)``). The window opens
    at the first call. Attributes: ``synced`` (viewer updates so far), ``closed_by_user`` (the window was
    closed before the run ended). close() closes the window (also a context manager).
    """

    def __init__(self, *, speedup: float | None = 1.0, sync_hz: float = 60.0,
                 launch: Callable | None = None, clock_s: Callable[[], float] = time.perf_counter,
                 sleep_s: Callable[[float], None] = time.sleep) -> None:
        if speedup is not None and not (isinstance(speedup, (int, float)) and math.isfinite(speedup) and speedup > 0):
            raise ValueError(f"speedup: expected a positive factor or None (unpaced), got {speedup!r}")
        if not (isinstance(sync_hz, (int, float)) and math.isfinite(sync_hz) and 1.0 <= sync_hz <= 1000.0):
            raise ValueError(f"sync_hz: expected 1..1000 updates per simulated second, got {sync_hz!r}")
        self.speedup = speedup
        self.sync_period_s = 1.0 / float(sync_hz)
        self._launch = launch if launch is not None else _launch_passive
        self._handle = None
        self._drawn = None  # (model, data) the window draws: kept alive until the window is gone
        self._next_sync_s = -math.inf
        self._pacer = WallPacer(speedup, clock_s=clock_s, sleep_s=sleep_s)
        self.synced = 0
        self.closed_by_user = False

    def __call__(self, chain) -> None:
        if self.closed_by_user:
            return
        if self._handle is None:
            self._open(chain)
        if not self._handle.is_running():
            self.closed_by_user = True
            return
        t_s = chain.time_s
        if t_s < self._next_sync_s - 1e-9:  # simulated times are sums of steps: allow their rounding
            return
        self._next_sync_s = t_s + self.sync_period_s
        self._handle.sync()
        self.synced += 1
        self._pacer.pace(t_s)

    def _open(self, chain) -> None:
        try:
            self._handle = self._launch(chain.model, chain.data)
        except ViewerUnavailable:
            raise
        except Exception as exc:  # GLFW could not open a window (no GLX, ...)
            raise ViewerUnavailable(f"the interactive viewer could not open a window ({type(exc).__name__}: {exc}); "
                                    f"check DISPLAY / WAYLAND_DISPLAY and MUJOCO_GL=glfw; {HEADLESS_HINT}") from exc
        self._drawn = (chain.model, chain.data)
        pts = chain.chain_points_m()
        with self._handle.lock():
            cam = self._handle.cam
            cam.lookat[:] = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
            cam.distance = max(1.0, 0.9 * chain.loop_length_m())
            cam.azimuth = 70.0
            cam.elevation = -20.0

    def close(self, *, timeout_s: float = 5.0) -> None:
        """Close the window and wait (up to timeout_s) for the viewer's thread to end: it draws from the plant's
        MjModel/MjData and tears its GL window down in its own (daemon) thread; freeing the model under it, or
        GLFW's exit handler running while it still tears down, crashes the process (seen: segfault at exit).
        mujoco.viewer.launch_passive starts that thread with target _launch_internal and does not expose it;
        Python names such a thread "Thread-N (_launch_internal)"."""
        if self._handle is not None:
            self._handle.close()
            deadline = time.monotonic() + timeout_s
            for thread in threading.enumerate():
                if thread is not threading.current_thread() and thread.name.endswith("(_launch_internal)"):
                    thread.join(max(0.0, deadline - time.monotonic()))
            self._handle = None
        self._drawn = None

    def __enter__(self) -> ScenarioViewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
