"""Motion commands: arm, disarm, spin, spindown, estop."""

from __future__ import annotations

import click

from robowrangler import units
from robowrangler.cli.negative_numbers import NumberArgsCommand
from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.stream import stream_telemetry
from robowrangler.errors import RoboWranglerError
from robowrangler.protocol.generated import State

SLOWEST_RAMP_MPS2 = 0.5  # lower bound of ramp_down_mps2: bounds the wait for the landing
_HOLD_ENDERS = (State.ESTOP, State.FAULT, State.DISARMED)


class HoldEnded(RoboWranglerError):
    """spin --hold: the device left the spin by itself or by another host (ESTOP, FAULT, DISARMED)."""


def _done(ctx: CliContext, command: str, state: State, human: str) -> None:
    ctx.result({"command": command, "state": state.name}, f"{human} (state {state.name})")


@click.command()
@pass_context
def arm(ctx: CliContext) -> None:
    """DISARMED -> ARMED (retries while the ESC arming hold after boot runs)."""
    with ctx.client() as rw:
        _done(ctx, "arm", rw.arm(timeout_s=ctx.timeout_s), "armed")


@click.command()
@pass_context
def disarm(ctx: CliContext) -> None:
    """ARMED, FAULT or ESTOP -> DISARMED (refused while the rope moves)."""
    with ctx.client() as rw:
        _done(ctx, "disarm", rw.disarm(), "disarmed")


@click.command(cls=NumberArgsCommand)
@click.argument("mps", type=float, metavar="MPS")
@click.option("--hold", "hold_s", type=Seconds(), default=None, metavar="SECONDS",
              help="Keep the link alive and stream telemetry this long, then spin down and wait for ARMED.")
@pass_context
def spin(ctx: CliContext, mps: float, hold_s: float | None) -> None:
    """Set the rope speed target to MPS (m/s); from ARMED this starts the spin-up.

    Without --hold the command returns after the ACK; the device then spins down by itself
    heartbeat_timeout_s after this process stops sending heartbeats.
    """
    units.mps_to_mmps(mps, argument="MPS")  # NaN/inf fail before connecting
    with ctx.client() as rw:
        first_event = len(rw.events)
        state = rw.spin(mps)
        if hold_s is None:
            ctx.note("no --hold: the device spins down heartbeat_timeout_s after this command exits")
            ctx.result({"command": "spin", "rope_speed_mps": mps, "state": state.name},
                       f"rope speed target {mps:g} m/s (state {state.name})")
            return
        landed = False
        seen: list = []  # the latest sample (a list: set inside the callback)
        flew = spinning = False

        def ended(sample) -> bool:  # another host's ESTOP or DISARM, or a fault: holding is over
            nonlocal flew, spinning
            seen[:] = [sample]
            flew = flew or sample.state == State.AIRBORNE
            # the device answers at once but queues telemetry: the first samples after the ACK may predate
            # the command (still ARMED, even DISARMED); only a stop after the spin was seen ends the hold
            spinning = spinning or sample.state in (State.SPINUP, State.AIRBORNE)
            return spinning and sample.state in _HOLD_ENDERS
        try:
            samples = stream_telemetry(ctx, rw, duration_s=hold_s, events_from=first_event, until=ended)
            last = seen[0] if seen else rw.latest_telemetry
            if spinning and last is not None and last.state in _HOLD_ENDERS:
                landed = True  # nothing to spin down: the rope is stopped or stopping by the device's own rule
                raise HoldEnded(f"spin --hold: the device went to {last.state.name} during the hold (another host or "
                                f"a fault: see `wrangler status`); the rope is not driven")
            rw.spindown()
            final = rw.wait_for_state(State.ARMED, timeout_s=ctx.timeout_s + abs(mps) / SLOWEST_RAMP_MPS2)
            landed = True
        finally:
            if not landed and rw.connected:
                _spindown_quietly(ctx, rw)
        target = last.rope_speed_target_mps if last is not None else mps
        held = f"held {mps:g} m/s for {hold_s:g} s"
        if abs(target - mps) > 0.0005:
            held = f"the target was changed to {target:g} m/s by another host during the {hold_s:g} s hold"
        elif not flew:
            held = (f"spun at {mps:g} m/s for {hold_s:g} s, but the loop never flew: {mps:g} m/s is under the ToV "
                    "guard (tov_mps x tov_margin)")
        ctx.result({"command": "spin", "rope_speed_mps": mps, "hold_s": hold_s, "samples": samples,
                    "airborne": flew, "rope_speed_target_mps": target, "state": final.state.name},
                   f"{held}, spun down (state {final.state.name})")


def _spindown_quietly(ctx: CliContext, rw) -> None:
    """Best-effort SPINDOWN while another error or Ctrl-C is already on its way out."""
    try:
        rw.spindown()
        ctx.note("spun down")
    except Exception as err:  # noqa: BLE001 - the original error is the one to report
        ctx.note(f"spin-down failed ({err}); the device lands on heartbeat loss")


@click.command()
@pass_context
def spindown(ctx: CliContext) -> None:
    """Controlled ramp to zero at ramp_down_mps2, landing the loop; ends ARMED."""
    with ctx.client() as rw:
        _done(ctx, "spindown", rw.spindown(), "spinning down")


@click.command()
@pass_context
def estop(ctx: CliContext) -> None:
    """Emergency stop: ESC minimum at once, latched until disarm."""
    with ctx.client() as rw:
        _done(ctx, "estop", rw.estop(), "emergency stop")
