"""Negative numbers as arguments: `wrangler loop -5`, `wrangler spin -1`, `wrangler param set guide_min_mm -3`.

click reads any word that starts with '-' as an option, so `wrangler loop -5` said "No such option '-5'" and the
user never learnt what the device thinks of -5 mm. A command of class NumberArgsCommand reads a word that is a
number (-5, -0.5, -.5, -1e3, -inf, -nan) as an argument instead; its options parse as before. The value then meets
the same checks as any other (finite and encodable here, the device's limits there).
"""

from __future__ import annotations

import re

import click

NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*([eE][-+]?\d+)?|\.\d+([eE][-+]?\d+)?|inf(inity)?|nan)$", re.IGNORECASE)


class NumberArgsCommand(click.Command):
    """A click command whose arguments may be negative numbers (see module doc)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        # A leading space keeps click's parser from taking the word for an option; float() ignores it. An option's
        # value (`--hold -3`) is taken as the value either way.
        return super().parse_args(ctx, [f" {a}" if NEGATIVE_NUMBER.match(a) else a for a in args])
