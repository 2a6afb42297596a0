"""Parameter commands: param list | get NAME | set NAME VALUE."""

from __future__ import annotations

import math

import click

from robowrangler import units
from robowrangler.cli.negative_numbers import NumberArgsCommand
from robowrangler.cli.context import CliContext, pass_context
from robowrangler.client import param_spec
from robowrangler.errors import InvalidArgument
from robowrangler.protocol.generated import PARAMS, ParamSpec


def _describe(spec: ParamSpec, value: float) -> dict:
    return {"name": spec.name, "value": value, "units": spec.units, "min": spec.min, "max": spec.max,
            "default": spec.default, "locked": spec.locked, "integer": spec.integer}


@click.group()
def param() -> None:
    """Read and set device parameters (SI units; see `wrangler param list`)."""


@param.command("list")
@pass_context
def list_(ctx: CliContext) -> None:
    """Every parameter: value, unit, default, range (* marks a value that differs from its default)."""
    with ctx.client() as rw:
        values = rw.params()
    rows = [_describe(p, values[p.name]) for p in PARAMS]
    ctx.result({"command": "param list", "params": rows}, _table(rows))


def _table(rows: list[dict]) -> str:
    """A fixed-width table with a header: name, value, unit, default, range, notes."""
    header = ("name", "value", "unit", "default", "range", "")
    body = [(r["name"], f"{r['value']:g}" + ("*" if r["value"] != r["default"] else ""), r["units"],
             f"{r['default']:g}", f"[{r['min']:g}, {r['max']:g}]",
             ", ".join(n for n, on in (("locked while armed", r["locked"]), ("integer", r["integer"])) if on))
            for r in rows]
    widths = [max(len(str(row[i])) for row in [header, *body]) for i in range(len(header))]
    right = {1, 3}  # numbers right-aligned
    lines = ["  ".join(str(cell).rjust(w) if i in right else str(cell).ljust(w)
                       for i, (cell, w) in enumerate(zip(row, widths))).rstrip() for row in [header, *body]]
    return "\n".join(lines)


@param.command()
@click.argument("name")
@pass_context
def get(ctx: CliContext, name: str) -> None:
    """Print the value of parameter NAME (any case)."""
    name = name.lower()
    spec = param_spec(name)  # unknown names fail before connecting
    with ctx.client() as rw:
        value = rw.get_param(name)
    ctx.result({"command": "param get", **_describe(spec, value)}, f"{name} = {value:g} {spec.units}")


@param.command("set", cls=NumberArgsCommand)
@click.argument("name")
@click.argument("value", type=float)
@pass_context
def set_(ctx: CliContext, name: str, value: float) -> None:
    """Set parameter NAME (any case) to VALUE (in its unit, see `param list`); prints the value the device now holds."""
    name = name.lower()
    spec = param_spec(name)
    units.param_to_float32(name, value)  # NaN fails before connecting
    if spec.integer and math.isfinite(value) and value != int(value):
        raise InvalidArgument(name, f"an integer ({spec.units})", value)
    with ctx.client() as rw:
        held = rw.set_param(name, value)
    ctx.result({"command": "param set", **_describe(spec, held)}, f"{name} = {held:g} {spec.units}")
