"""Motion commands: arm, disarm, spin, spindown, estop."""

from __future__ import annotations

import click

from robowrangler import units
from robowrangler.cli.context import CliContext, Seconds, pass_context
from robowrangler.cli.stream import stream_telemetry
from robowrangler.protocol.generated import State

SLOWEST_RAMP_MPS2 = 0.5  # lower bound of ramp_down_mps2: bounds the wait for the landing


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


@click.command()
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
        try:
            samples = stream_telemetry(ctx, rw, duration_s=hold_s, events_from=first_event)
            rw.spindown()
            final = rw.wait_for_state(State.ARMED, timeout_s=ctx.timeout_s + abs(mps) / SLOWEST_RAMP_MPS2)
            landed = True
        finally:
            if not landed and rw.connected:
                _spindown_quietly(ctx, rw)
        ctx.result({"command": "spin", "rope_speed_mps": mps, "hold_s": hold_s, "samples": samples,
                    "state": final.state.name},
                   f"held {mps:g} m/s for {hold_s:g} s, spun down (state {final.state.name})")


def _spindown_quietly(ctx: CliContext, rw) -> None:
    """Best-effort SPINDOWN while another error or Ctrl-C is already on its way out."""
    try:
        rw.spindown()
        ctx.note("spun down")
    except Exception as err:  # noqa: BLE001 - the original error is the one to report
        ctx.note(f"spin-down after the interruption failed ({err}); the device lands on heartbeat loss")


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
