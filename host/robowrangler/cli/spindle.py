"""Spindle and grasp commands: home, loop, relax, retract, grasp, release.

Guide positions are given and shown in mm from home (as the device's guide_min_mm/guide_max_mm
parameters are); the Python API takes metres.

A guide move needs a live host, as a spinning rope does: the device stops the guide where it is when no
host has been heard for heartbeat_timeout_s (no machine moves unwatched). So home, loop, retract and grasp
wait for the move to end, keeping the link alive and showing progress on stderr; `loop --no-wait`
returns at once and the guide goes on only while another tool keeps the link alive (a `wrangler watch`,
or any tool through `wrangler proxy`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import click

from robowrangler import units
from robowrangler.cli.negative_numbers import NumberArgsCommand
from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.progress import Progress
from robowrangler.errors import InvalidArgument, RoboWranglerError, StateTimeout
from robowrangler.protocol.generated import SPINDLE_PERIOD_MS, SpindleFlag, State
from robowrangler.telemetry import TelemetrySample

_WITHIN = dict(type=Seconds(positive=True), metavar="SECONDS", show_default=True)
_HEARTBEAT_NOTE = "the device stops the spindle heartbeat_timeout_s after this command exits"
_NO_WAIT_NOTE = ("--no-wait: the guide goes on only while a host is alive; alone, it stops where it is "
                 "heartbeat_timeout_s after this command exits")


class NothingGrasped(RoboWranglerError):
    """A grasp or retract reached the end of the stroke without the load that secures an object."""


class GuideNotThere(RoboWranglerError):
    """home or loop ran out of --within before the guide got there; says where it is and what follows."""


def _wait_for_guide(ctx: CliContext, rw, done, *, within_s: float, what: str, target: str) -> object:
    """Wait (with progress on stderr) until done(sample); GuideNotThere naming the guide's position if not."""
    progress = Progress(ctx)
    start_s = time.monotonic()

    def check(sample) -> bool:
        progress.show(f"{what}: guide at {_guide_mm(sample):g} mm{target}, {time.monotonic() - start_s:4.1f} s "
                      f"of {within_s:g} s", time.monotonic())
        return done(sample)

    try:
        return rw.wait_for(check, timeout_s=within_s, expected=what)
    except StateTimeout:
        sample = rw.latest_telemetry
        where = f"{_guide_mm(sample):g} mm" if sample is not None else "unknown"
        moving = sample is not None and SpindleFlag.MOVING in sample.spindle_flags
        raise GuideNotThere(f"{what}: not done within {within_s:g} s: the guide is at {where}{target}"
                            + (" and still moving; the device stops it there heartbeat_timeout_s after this command "
                               "exits: give a longer --within" if moving else "")) from None
    finally:
        progress.end_line()


def _settled_at(target_m: float) -> Callable[[TelemetrySample], bool]:
    """done() for a loop move: the device reports the target and no moving speed, after its spindle loop has acted
    on the target. The first samples that carry a new target may come before the loop's next step (every
    SPINDLE_PERIOD_MS of the device's time): they say "not moving" with the guide where it was. So a sample
    counts once MOVING has been seen, or from two spindle periods (device time) after the target first showed."""
    first_s: list[float] = []
    seen_moving = False

    def done(sample: TelemetrySample) -> bool:
        nonlocal seen_moving
        if abs(sample.guide_target_m - target_m) >= 1e-6:
            return False
        moving = SpindleFlag.MOVING in sample.spindle_flags
        seen_moving |= moving
        if not first_s:
            first_s.append(sample.time_s)
        acted = seen_moving or sample.time_s - first_s[0] >= 2 * SPINDLE_PERIOD_MS / 1000
        return acted and not moving
    return done


GUIDE_WIRE_LIMIT_MM = units.INT32_MAX / 1000.0  # SET_LOOP carries um in an int32


def guide_target_m(guide_mm: float) -> float:
    """GUIDE_MM (mm, as typed) -> m for the client; what the wire cannot carry is refused in mm, the
    argument's unit (the device range-checks the rest against guide_min_mm..guide_max_mm)."""
    x = units.check_real("GUIDE_MM", guide_mm, allow_inf=False)
    if abs(x) > GUIDE_WIRE_LIMIT_MM:
        raise InvalidArgument("GUIDE_MM",
                              f"a guide position encodable on the wire (|x| <= {GUIDE_WIRE_LIMIT_MM:.3f} mm)", x)
    return units.mm_to_m(x)


def _guide_mm(sample) -> float:
    return round(units.m_to_mm(sample.guide_position_m), 3)


@click.command()
@click.option("--within", "within_s", default=60.0, help="Wait this long for the end stop.", **_WITHIN)
@pass_context
def home(ctx: CliContext, within_s: float) -> None:
    """Drive the guide to the home end (stall or limit switch) and set position 0 there."""
    with ctx.client() as rw:
        rw.home()
        done = _wait_for_guide(ctx, rw, lambda s: SpindleFlag.HOMED in s.spindle_flags
                               and SpindleFlag.HOMING not in s.spindle_flags, within_s=within_s, what="homing",
                               target=" (looking for the home end)")
    ctx.result({"command": "home", "state": done.state.name, "guide_mm": _guide_mm(done)},
               f"homed (guide at {_guide_mm(done):g} mm, state {done.state.name})")


@click.command(cls=NumberArgsCommand)
@click.argument("guide_mm", type=float, metavar="GUIDE_MM")
@click.option("--within", "within_s", default=30.0, help="Wait this long for the guide to get there.", **_WITHIN)
@click.option("--no-wait", is_flag=True,
              help="Return once the device accepted the target. The guide moves only while a host is alive: "
                   "alone it stops where it is heartbeat_timeout_s later; keep a tool connected (wrangler watch, "
                   "or a spin --hold through wrangler proxy) for it to get there.")
@pass_context
def loop(ctx: CliContext, guide_mm: float, within_s: float, no_wait: bool) -> None:
    """Move the rope guide to GUIDE_MM from home (larger = smaller loop); needs a homed spindle.

    Waits for the guide (progress on stderr); the guide moves only while a host is alive (see --no-wait)."""
    target_m = guide_target_m(guide_mm)  # NaN/inf/beyond the wire fail before connecting
    with ctx.client() as rw:
        state = rw.set_loop(target_m)
        if no_wait:
            ctx.note(_NO_WAIT_NOTE)
            ctx.result({"command": "loop", "guide_target_mm": guide_mm, "state": state.name},
                       f"guide target {guide_mm:g} mm (state {state.name})")
            return
        done = _wait_for_guide(ctx, rw, _settled_at(target_m), within_s=within_s, what="loop",
                               target=f" of the target {guide_mm:g} mm")
    ctx.result({"command": "loop", "guide_target_mm": guide_mm, "guide_mm": _guide_mm(done), "state": done.state.name},
               f"guide at {_guide_mm(done):g} mm (target {guide_mm:g} mm, state {done.state.name})")


@click.command()
@pass_context
def relax(ctx: CliContext) -> None:
    """SPINUP or AIRBORNE -> RELAX: stop the rope so the loop settles onto the object."""
    with ctx.client() as rw:
        state = rw.relax()
    ctx.result({"command": "relax", "state": state.name}, f"relaxing (state {state.name})")


def _until_held(ctx: CliContext, rw, command: str, within_s: float) -> None:
    progress = Progress(ctx)
    start_s = time.monotonic()

    def check(sample) -> bool:
        progress.show(f"{command}: {sample.state.name}, guide at {_guide_mm(sample):g} mm, load "
                      f"{sample.spindle_load_pct:g} %, {time.monotonic() - start_s:4.1f} s", time.monotonic())
        return sample.state in (State.HOLD, State.ARMED)

    try:
        end = rw.wait_for(check, timeout_s=within_s, expected=(State.HOLD, State.ARMED))
    finally:
        progress.end_line()
    if end.state != State.HOLD:
        raise NothingGrasped(f"{command}: the guide reached the end of the stroke ({_guide_mm(end):g} mm) without "
                             "securing a load; nothing is held (state ARMED)")
    ctx.note(_HEARTBEAT_NOTE)
    ctx.result({"command": command, "state": end.state.name, "guide_mm": _guide_mm(end),
                "spindle_load_pct": end.spindle_load_pct},
               f"holding at {_guide_mm(end):g} mm, load {end.spindle_load_pct:g} % (state HOLD)")


@click.command()
@click.option("--within", "within_s", default=30.0, help="Wait this long for HOLD.", **_WITHIN)
@pass_context
def retract(ctx: CliContext, within_s: float) -> None:
    """Reel the loop in until the load secures the object (HOLD); exit 1 if the stroke ends first."""
    with ctx.client() as rw:
        rw.retract()
        _until_held(ctx, rw, "retract", within_s)


@click.command()
@click.option("--within", "within_s", default=30.0, help="Wait this long for HOLD.", **_WITHIN)
@pass_context
def grasp(ctx: CliContext, within_s: float) -> None:
    """AIRBORNE -> relax onto the object -> retract -> HOLD; exit 1 if the stroke ends first."""
    with ctx.client() as rw:
        rw.grasp()
        _until_held(ctx, rw, "grasp", within_s)


@click.command()
@pass_context
def release(ctx: CliContext) -> None:
    """HOLD -> extend the guide by release_mm to let the object go -> ARMED."""
    with ctx.client() as rw:
        state = rw.release()
    ctx.result({"command": "release", "state": state.name}, f"released (state {state.name})")
