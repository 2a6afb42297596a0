"""Parameter commands: param list | get NAME | set NAME VALUE."""

from __future__ import annotations

import math

import click

from robowrangler import units
from robowrangler.cli.context import CliContext, pass_context
from robowrangler.client import param_spec
from robowrangler.errors import InvalidArgument
from robowrangler.protocol.generated import PARAMS, ParamSpec


def _describe(spec: ParamSpec, value: float) -> dict:
    return {"name": spec.name, "value": value, "units": spec.units, "min": spec.min, "max": spec.max,
            "default": spec.default, "locked": spec.locked}


@click.group()
def param() -> None:
    """Read and set device parameters (SI units; see `wrangler param list`)."""


@param.command("list")
@pass_context
def list_(ctx: CliContext) -> None:
    """Every parameter with its value, unit and range."""
    with ctx.client() as rw:
        values = rw.params()
    rows = [_describe(p, values[p.name]) for p in PARAMS]
    width = max(len(p.name) for p in PARAMS)
    human = "\n".join(f"{r['name']:<{width}}  {r['value']:>10g} {r['units']:<11} [{r['min']:g}, {r['max']:g}]"
                      + ("  locked" if r["locked"] else "") for r in rows)
    ctx.result({"command": "param list", "params": rows}, human)


@param.command()
@click.argument("name")
@pass_context
def get(ctx: CliContext, name: str) -> None:
    """Print the value of parameter NAME."""
    spec = param_spec(name)  # unknown names fail before connecting
    with ctx.client() as rw:
        value = rw.get_param(name)
    ctx.result({"command": "param get", **_describe(spec, value)}, f"{name} = {value:g} {spec.units}")


@param.command("set")
@click.argument("name")
@click.argument("value", type=float)
@pass_context
def set_(ctx: CliContext, name: str, value: float) -> None:
    """Set parameter NAME to VALUE (SI unit); prints the value the device now holds."""
    spec = param_spec(name)
    units.param_to_float32(name, value)  # NaN fails before connecting
    if spec.integer and math.isfinite(value) and value != int(value):
        raise InvalidArgument(name, f"an integer ({spec.units})", value)
    with ctx.client() as rw:
        held = rw.set_param(name, value)
    ctx.result({"command": "param set", **_describe(spec, held)}, f"{name} = {held:g} {spec.units}")
