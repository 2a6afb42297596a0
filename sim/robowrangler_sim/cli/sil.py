"""Simulation commands: `wrangler sil` (a SIL device on UDP) and `wrangler demo` (the end-to-end demo).

Plugins of `wrangler` from the simulator distribution (robowrangler-sim, entry point group `robowrangler.cli`):
the host package never imports this module. The native SIL build is looked up when a command runs.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import click

from robowrangler.cli.context import CliContext, pass_context
from robowrangler.cli.signals import sigterm_as_interrupt
from robowrangler.errors import RoboWranglerError



class SimulatorUnavailable(RoboWranglerError):
    """The SIL firmware or the simulator cannot run here; the message says what to build or install."""


class ScenarioFailed(RoboWranglerError):
    """A scenario did not reach its judgement: the chain simulation diverged or the firmware stopped the script."""


def _scenario_names() -> tuple[str, ...]:
    from robowrangler_sim.scenarios.catalogue import scenario_names

    return scenario_names()


def _headless_gl(ctx: click.Context, param: click.Parameter, value: str | None) -> str | None:
    """--render: pick MuJoCo's headless OpenGL (OSMesa) unless the user chose one, before --scenario's check
    imports MuJoCo (the backend is fixed at its first import)."""
    if value is not None:
        os.environ.setdefault("MUJOCO_GL", "osmesa")
        if os.environ["MUJOCO_GL"] in ("osmesa", "egl"):
            os.environ.setdefault("PYOPENGL_PLATFORM", os.environ["MUJOCO_GL"])
    return value


class ScenarioName(click.ParamType):
    """A scenario name, checked against the simulator's catalogue when used (the catalogue imports MuJoCo,
    so it is loaded only when --scenario is given or --help is shown)."""

    name = "scenario"

    def get_metavar(self, param: click.Parameter, ctx: click.Context) -> str:
        names = _scenario_names()
        return "[" + "|".join(names) + "]" if names else "NAME"

    def convert(self, value, param, ctx):
        names = _scenario_names()
        if value not in names:
            self.fail(f"expected one of {', '.join(names)}, got {value!r}", param, ctx)
        return value


class WifiSpec(click.ParamType):
    """The SIL board's NINA WiFi module and its faults (robowrangler_sim.sil.wifi_module.WifiModule.parse)."""

    name = "wifi"

    def get_metavar(self, param: click.Parameter, ctx: click.Context) -> str:
        return "SPEC"

    def convert(self, value, param, ctx):
        from robowrangler_sim.sil.wifi_module import WifiModule, WifiModuleError

        if not isinstance(value, str):
            return value
        try:
            return WifiModule.parse(value)
        except WifiModuleError as exc:
            self.fail(str(exc), param, ctx)


def _sil_modules():
    from robowrangler_sim import demo, sil

    return sil, demo


@click.command("sil")
@click.option("--port", "cmd_port", type=click.IntRange(0, 65535), default=14550, show_default=True,
              help="UDP port on 127.0.0.1 the SIL device listens on (0 = any free port).")
@click.option("--speedup", type=click.FloatRange(min=0.0, min_open=True), default=1.0, show_default=True,
              help="Simulated seconds per wall second (1 = real time; hosts' heartbeats run on the wall clock).")
@click.option("--unpaced", is_flag=True, help="Run as fast as the machine goes (scripted hosts only).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Plant noise seed.")
@click.option("--duration", "duration_s", type=click.FloatRange(min=0.0, min_open=True), default=None,
              metavar="SECONDS", help="Stop after this much simulated time (default: until Ctrl-C).")
@click.option("--state-file", default=None, metavar="PATH",
              help="The SIL device's flash (key, parameters, boot counter); default: a temporary one.")
@click.option("--model", "model_file", default=None, metavar="FILE", type=click.Path(exists=True, dir_okay=False),
              help="Model written by `wrangler diagnose` (model.json): refitted drive and spindle parameters and "
                   "effect terms; or, with --scenario, a loop model (loop_model.json): the rope chain's shape table "
                   "with the loop effects.")
@click.option("--scenario", "scenario", type=ScenarioName(), default=None,
              help="Run a wrangling scenario with the firmware in the loop instead of serving a device: the "
                   "rope chain (MuJoCo) is the plant; the simulation judges the grasp. Unpaced.")
@click.option("--links", "n_links", type=click.IntRange(10, 80), default=20, show_default=True,
              help="Chain links of the scenario's rope model.")
@click.option("--render", "render_dir", type=click.Path(file_okay=False, writable=True), default=None,
              metavar="DIR", is_eager=True, callback=_headless_gl, help="With --scenario: write PNG frames and an MP4 of the run to DIR "
                                  "(headless: MUJOCO_GL=osmesa, Debian libosmesa6).")
@click.option("--viewer", is_flag=True,
              help="With --scenario: watch the run in MuJoCo's interactive viewer, paced by --speedup (--unpaced: as "
                   "fast as it goes). Needs a display (DISPLAY or WAYLAND_DISPLAY) and MUJOCO_GL unset or glfw.")
@click.option("--foxglove", "foxglove_port", type=click.IntRange(0, 65535), is_flag=False, flag_value=8765,
              default=None, metavar="[PORT]",
              help="With --scenario: serve the run live to Foxglove (ws://127.0.0.1:PORT, default 8765; foxglove-sdk): "
                   "the loop's contour (/loop/observation) and 3D scene (/loop/scene) at 30 Hz, the firmware's "
                   "telemetry, events and commands; paced by --speedup (--unpaced: as fast as it goes).")
@click.option("--shape-table", "shape_table", type=click.Path(dir_okay=False), default=None, metavar="FILE",
              help="With --scenario: the rope chain's shape table (JSON, e.g. from `wrangler identify`) instead of "
                   "the shipped default.")
@click.option("--wifi", "wifi", type=WifiSpec(), default=None,
              help="The board's NINA WiFi module and its faults, plant time in seconds, comma-separated: "
                   "boot=never (a module that never answers: NO_MODULE after 2 s, LED on), boot=S (its ready line "
                   "S after reset), associate=S, lost=START-END (the access point out of reach; START- for good), "
                   "busy_us=N (its ready line busy N us after each call), slow_from=S. Default: a healthy module.")
@pass_context
def sil_command(ctx: CliContext, cmd_port: int, speedup: float, unpaced: bool, seed: int,
                duration_s: float | None, state_file: str | None, scenario: str | None, n_links: int,
                render_dir: str | None, viewer: bool, shape_table: str | None, model_file: str | None = None,
                foxglove_port: int | None = None, wifi=None) -> None:
    """Run a simulated RoboWrangler (SIL firmware + drive plant) on udp://127.0.0.1:PORT.

    Point any wrangler command or the Python client at it: it speaks the board's protocol. It is provisioned
    over its (pseudo-terminal) USB serial with --key-file's key (or a new one, whose file is printed), as a
    board would be.

    With --scenario NAME it runs a wrangle instead (home, spin up, GRASP, pull) with the firmware driving the
    rope chain, shows progress on stderr and prints the simulation's verdict (secured / slipped; held / lost
    for the door handle). Exit status 1 if the chain simulation diverged or the firmware stopped the script.
    With --viewer as well, MuJoCo's interactive viewer shows the rope chain while the firmware runs (exit status 1,
    naming MUJOCO_GL and DISPLAY, where no display can show it). With --foxglove, Foxglove shows it live
    (open ws://127.0.0.1:8765): the loop's contour and 3D scene beside the telemetry, events and commands.
    """
    if foxglove_port is not None and scenario is None:
        raise click.UsageError("--foxglove needs --scenario (only a scenario simulates the loop; for a plain SIL "
                               "device's stream run `wrangler proxy --foxglove` or `wrangler watch --foxglove` "
                               "against it)")
    if viewer and scenario is None:
        raise click.UsageError("--viewer needs --scenario")
    if wifi is not None and scenario is not None:
        raise click.UsageError("--wifi shapes a served SIL device's WiFi module; a --scenario runs its own host "
                               "over a healthy link")
    if viewer and render_dir is not None:
        raise click.UsageError("--viewer and --render cannot be combined: MuJoCo uses one OpenGL backend per process "
                               "(GLFW windows for --viewer, headless OSMesa for --render)")
    table = None
    if shape_table is not None:
        if scenario is None:
            raise click.UsageError("--shape-table needs --scenario (the shape table drives the rope chain, which only "
                                   "a scenario simulates)")
        table = _load_shape_table(shape_table)
    if model_file is not None:
        table = _loop_model_table(ctx, model_file, scenario=scenario, table=table)
    if scenario is not None:
        _run_scenario(ctx, scenario, seed=seed, n_links=n_links, render_dir=render_dir, viewer=viewer,
                      viewer_speedup=None if unpaced else speedup, table=table, foxglove_port=foxglove_port)
        return
    if render_dir is not None:
        raise click.UsageError("--render needs --scenario")
    sil_pkg, _ = _sil_modules()
    try:
        session = sil_pkg.SilSession(speedup=None if unpaced else speedup, seed=seed, cmd_port=cmd_port,
                                     trace_every=0, key=ctx.key, state_file=state_file, model=model_file, wifi=wifi)
        session.start()
    except sil_pkg.SilError as exc:
        raise SimulatorUnavailable(str(exc)) from exc
    key_note = "your --key-file"
    if ctx.key is None:  # a fresh key for this run, in a private file the other commands can use
        key_path = Path(tempfile.mkdtemp(prefix="wrangler_sil_")) / "link.key"
        fd = os.open(key_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(session.key.hex() + "\n")
        key_note = f"a new key in {key_path} (export ROBOWRANGLER_KEY_FILE={key_path})"
    try:
        # `kill %1` (SIGTERM; a background job ignores Ctrl-C's SIGINT) stops it as Ctrl-C does: firmware stopped,
        # temporary flash removed, exit 130
        with sigterm_as_interrupt() as stop:
            session.run_in_background()
            if ctx.json_mode:
                ctx.json_line({"type": "ready", "url": session.cmd_url, "serial": session.serial_path,
                               "key": key_note, "speedup": None if unpaced else speedup,
                               "firmware_pid": session.firmware_pid})
            else:
                pace = "unpaced" if unpaced else f"speed-up {speedup:g}x"
                ctx.note(f"SIL device on {session.cmd_url} ({pace}), USB serial {session.serial_path}, "
                         f"provisioned with {key_note}; Ctrl-C (or SIGTERM) to stop")
            while duration_s is None or session.time_s < duration_s:
                stop.check()
                session.check()
                time.sleep(0.05)
            session.check()
    except sil_pkg.SilError as exc:
        raise SimulatorUnavailable(f"the SIL stopped: {exc}") from exc
    finally:
        session.stop()
    wifi_counters = session.wifi_counters()
    wifi_data = {k: wifi_counters[k] for k in ("state", "boot_ms", "losses", "deferred", "module_busy",
                                                "module_hangs", "ready_waits_expired")}
    ctx.result({"command": "sil", "simulated_s": round(session.time_s, 3), "wifi": wifi_data},
               f"SIL stopped after {session.time_s:.3f} simulated seconds (WiFi {wifi_data['state']}: "
               f"{wifi_data['losses']} losses, {wifi_data['deferred']} deferred reconnects, "
               f"{wifi_data['module_busy']} passes with the module busy)")


def _load_shape_table(path: str):
    """The shape table at ``path``; a missing or malformed file is a usage error naming it."""
    from robowrangler_sim.shape_table import ShapeTable, ShapeTableError

    try:
        return ShapeTable.load(path)
    except (OSError, ShapeTableError) as exc:
        detail = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise click.BadParameter(f"{path}: {detail}", param_hint="--shape-table") from exc


def _loop_model_table(ctx: CliContext, path: str, *, scenario: str | None, table):
    """A loop model (loop_model.json of `wrangler diagnose`) gives the rope chain its shape table, with the diagnosed
    steady loop effects baked in; a drive model leaves the table as it is."""
    from robowrangler_sim.diagnose.errors import DiagnoseError
    from robowrangler_sim.diagnose.loop.model_file import NOT_IN_CHAIN, LoopModel, is_loop_model_file

    if not is_loop_model_file(path):
        return table
    if scenario is None:
        raise click.UsageError("--model: a loop model (robowrangler.loop_model) drives the rope chain, which only "
                               "--scenario simulates")
    if table is not None:
        raise click.UsageError("--model (a loop model) and --shape-table both give the rope chain's shape table")
    try:
        model = LoopModel.load(path)
        out = model.shape_table()
    except DiagnoseError as exc:
        raise click.BadParameter(str(exc), param_hint="--model") from exc
    left = [e for e in model.effects if e in NOT_IN_CHAIN or e == "transient_wave_dynamics"]
    ctx.note(f"loop model {path}: shape table with {sorted(set(model.effects) - set(left)) or 'no'} loop effects"
             + (f"; not in the scenario's chain: {', '.join(left)}" if left else ""))
    return out


def _run_scenario(ctx: CliContext, name: str, *, seed: int, n_links: int, render_dir: str | None,
                  viewer: bool = False, viewer_speedup: float | None = 1.0, table=None,
                  foxglove_port: int | None = None) -> None:
    watch = None
    if viewer:  # before anything runs (or imports MuJoCo's viewer): say what is missing
        from robowrangler_sim.scenarios.viewer import HEADLESS_HINT, ScenarioViewer, display_problem, glfw_problem

        problem = display_problem(ctx.env.environ)
        if problem is None and (glfw := glfw_problem()) is not None:
            problem = (f"the interactive viewer cannot open a window: {glfw}; check DISPLAY / WAYLAND_DISPLAY "
                       f"(MUJOCO_GL=glfw); {HEADLESS_HINT}")
        if problem is not None:
            raise SimulatorUnavailable(f"--viewer: {problem}")
        watch = ScenarioViewer(speedup=viewer_speedup)
    sil_pkg, _ = _sil_modules()
    from robowrangler_sim.scenarios import run_scenario
    from robowrangler_sim.scenarios.viewer import ViewerUnavailable

    from robowrangler_sim.scenarios.runner import ScenarioInterrupted

    server = live = None
    if foxglove_port is not None:
        from robowrangler.recorder.live_view import FoxgloveLiveView
        from robowrangler_sim.scenarios.live_loop import ScenarioLiveView

        server = FoxgloveLiveView(port=foxglove_port)
        live = ScenarioLiveView(server, speedup=viewer_speedup)
        pace = "as fast as it goes" if viewer_speedup is None else f"paced at {viewer_speedup:g}x"
        ctx.note(f"live in Foxglove at {server.url} (the loop on /loop/observation and /loop/scene, {pace})")
    try:
        with sigterm_as_interrupt():  # SIGTERM ends a scenario as Ctrl-C does: it says what it left
            outcome = run_scenario(name, seed=seed, n_links=n_links, progress=ctx.note, render_dir=render_dir,
                                   watch=watch, table=table, live=live)
    except ScenarioInterrupted as stop:
        ctx.note(_what_was_left(name, stop, render_dir))
        raise KeyboardInterrupt from None
    except sil_pkg.SilError as exc:
        raise SimulatorUnavailable(str(exc)) from exc
    except ViewerUnavailable as exc:
        raise SimulatorUnavailable(f"--viewer: {exc}") from exc
    finally:
        if watch is not None:
            watch.close()
        if live is not None:
            live.close()
            server.close()
    if live is not None:
        ctx.note(f"Foxglove: {live.contours} loop contours, {live.recorder.telemetry_count} telemetry, "
                 f"{live.recorder.event_count} events, {live.recorder.command_count} commands served")
    if watch is not None:
        ctx.note(f"viewer: {watch.synced} updates" + (" (window closed before the end)" if watch.closed_by_user else ""))
    data = {"command": "sil", "scenario": name, "verdict": outcome.verdict, "secured": outcome.secured,
            "grasp_end": outcome.grasp_end, "guide_at_grasp_end_mm": round(outcome.guide_at_grasp_end_mm, 2),
            "peak_guide_load_n": round(outcome.peak_guide_load_n, 3),
            "follow_ratio": None if outcome.follow_ratio != outcome.follow_ratio else round(outcome.follow_ratio, 3),
            "touching_fraction": round(outcome.touching_fraction, 3),
            "mean_pull_force_n": round(outcome.mean_pull_force_n, 3), "drag_force_n": round(outcome.drag_force_n, 3),
            "door_opening_deg": (None if outcome.door_opening_deg != outcome.door_opening_deg
                                 else round(outcome.door_opening_deg, 2)),
            "firmware_path": ["->".join(step[:2]) + f" ({step[2]})" for step in outcome.firmware_path],
            "diverged": outcome.diverged, "simulated_s": round(outcome.simulated_s, 3),
            "wall_s": round(outcome.wall_s, 2), "seed": seed, "links": n_links, "files": outcome.frames_written,
            "viewer_updates": None if watch is None else watch.synced,
            "foxglove_contours": None if live is None else live.contours,
            "shape_table": outcome.shape_table_source}
    files = f"; {len(outcome.frames_written)} files in {render_dir}" if outcome.frames_written else ""
    path = outcome.firmware_path
    states = " -> ".join([path[0][0]] + [f"{to} ({cause})" for _, to, cause in path]) if path else "-"
    ctx.result(data, f"firmware state path: {states}\n"
                     f"{name}: {outcome.verdict} (RETRACT ended: {outcome.grasp_end}, "
                     + ("" if outcome.kind == "door" else f"follow {data['follow_ratio']}, ")
                     + f"rope touching {100 * outcome.touching_fraction:.0f} %, mean pull "
                     f"{outcome.mean_pull_force_n:.2f} N"
                     + ("" if data["door_opening_deg"] is None else f", door opened {outcome.door_opening_deg:.1f} deg")
                     + f"; {outcome.simulated_s:.1f} simulated s in "
                     f"{outcome.wall_s:.1f} s){files}")
    if outcome.secured is not None:
        ctx.note(_explain_verdict(name, outcome))
    if outcome.secured is None:
        raise ScenarioFailed(f"scenario {name}: {outcome.verdict}")


def _what_was_left(name: str, stop, render_dir: str | None) -> str:
    """One line for an interrupted scenario: where it stopped, the firmware's states so far, the files left."""
    o = stop.outcome
    path = (" -> ".join([o.firmware_path[0][0]] + [to for _, to, _ in o.firmware_path]) if o.firmware_path
            else "unchanged since boot")
    pngs = [f for f in o.frames_written if f.endswith(".png")]
    mp4s = [f for f in o.frames_written if f.endswith(".mp4")]
    files = (f"; left in {render_dir}: {len(pngs)} PNG frames" + (f" and {Path(mp4s[0]).name} (the run so far)"
                                                                 if mp4s else "")) if render_dir else ""
    return (f"scenario {name} interrupted in phase {stop.phase} at {o.simulated_s:.1f} simulated s, no verdict; "
            f"firmware states {path}; the SIL firmware is stopped{files}")


def explain_criteria(spec) -> str:
    """What the verdict of a scenario means, with its thresholds (the judged half of the pull)."""
    script = spec.script
    if spec.kind == "door":
        return (f"held = the rope kept touching the lever in at least {100 * script.contact_fraction:.0f} % of the "
                "judged samples while the robot pulled (a fixture does not follow)")
    return (f"secured = over the judged part of the pull the object followed the module (follow = its displacement "
            f"/ the module's, at least {script.follow_fraction:g}) and the rope touched it in at least "
            f"{100 * script.contact_fraction:.0f} % of the samples; follow above 1 means it went further than the "
            "module (pushed or rolled ahead)")


def _explain_verdict(name: str, outcome) -> str:
    from robowrangler_sim.scenarios.catalogue import get_scenario
    from robowrangler_sim.scenarios.table_i_sil import why_outcome

    spec = get_scenario(name)
    return f"{explain_criteria(spec)}. Here: {why_outcome(outcome, spec)}"


@click.command("demo")
@click.option("--out", "out_png", type=click.Path(dir_okay=False, writable=True), default="out/demo.png",
              show_default=True, help="Where to write the plot (PNG).")
@click.option("--speedup", type=click.FloatRange(0.1, 3.0), default=1.0, show_default=True,
              help="Simulated seconds per wall second.")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Plant noise seed.")
@click.option("--wrangle", "wrangle_dir", type=click.Path(file_okay=False, writable=True), default="out/wrangle",
              show_default=True, metavar="DIR",
              help="Then a wrangle (the mug scenario, firmware in the loop, MuJoCo rope chain): PNG frames and an "
                   "MP4 in DIR (about a minute).")
@click.option("--no-wrangle", is_flag=True, help="Only the speed demo.")
@pass_context
def demo_command(ctx: CliContext, out_png: str, speedup: float, seed: int, wrangle_dir: str,
                 no_wrangle: bool) -> None:
    """The end-to-end demo on the simulated rope: arm, 4 m/s, 6 m/s, spin down, disarm, plot; then a wrangle
    of a mug, rendered (`wrangler sil --scenario NAME` runs any other)."""
    if not no_wrangle:
        _headless_gl(None, None, wrangle_dir)  # before anything imports MuJoCo
    sil_pkg, demo = _sil_modules()
    try:
        result = demo.run_demo(out_png, speedup=speedup, seed=seed, progress=ctx.note)
    except sil_pkg.SilError as exc:
        raise SimulatorUnavailable(str(exc)) from exc
    wrangle = None
    if not no_wrangle:
        from robowrangler_sim.scenarios import run_scenario

        ctx.note(f"wrangle: the mug scenario with the firmware in the loop, frames to {wrangle_dir}")
        try:
            wrangle = run_scenario("mug", seed=seed, progress=ctx.note, render_dir=wrangle_dir)
        except sil_pkg.SilError as exc:
            raise SimulatorUnavailable(str(exc)) from exc

    def fmt(x: float | None) -> str:
        return "did not settle" if x is None else f"{x:.2f} s"

    wrangle_text = "" if wrangle is None else (
        f"\nwrangle (mug): {wrangle.verdict}; {len(wrangle.frames_written)} files in {wrangle_dir}")
    ctx.result(
        {"command": "demo", "plot": str(result.plot_path), "settle_4_mps_s": result.settle_4_mps_s,
         "settle_6_mps_s": result.settle_6_mps_s, "min_airborne_speed_mps": result.min_airborne_speed_mps,
         "telemetry_samples": result.samples, "wall_s": round(result.wall_s, 2),
         "wrangle": None if wrangle is None else {"scenario": "mug", "verdict": wrangle.verdict,
                                                   "files": [str(f) for f in wrangle.frames_written]}},
        f"plot written to {result.plot_path}\n"
        f"0 -> 4 m/s settled within 2 % in {fmt(result.settle_4_mps_s)}; 4 -> 6 m/s in {fmt(result.settle_6_mps_s)}; "
        f"slowest airborne sample {result.min_airborne_speed_mps:.2f} m/s (guard 2.99 m/s)" + wrangle_text,
    )
    if wrangle is not None and wrangle.secured is None:
        raise ScenarioFailed(f"demo wrangle: {wrangle.verdict}")
