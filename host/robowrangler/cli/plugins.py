"""Verbs of `wrangler` that other distributions add: the simulator (robowrangler-sim) registers `sil`, `demo`
and later `diagnose` / `identify` through the entry point group `robowrangler.cli`, whose target returns a list
of click commands. The host distribution never imports the simulator: without it, those verbs still appear and
answer with the package to add (exit 1), instead of "no such command".
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import metadata

import click

from robowrangler.errors import RoboWranglerError

ENTRY_POINT_GROUP = "robowrangler.cli"
SIMULATOR_DISTRIBUTION = "robowrangler-sim"

# The verbs the simulator distribution provides, with a line for `wrangler --help` when it is absent.
SIMULATOR_VERBS: dict[str, str] = {
    "sil": "Run a simulated device (software in the loop).",
    "demo": "The end-to-end demo on the simulated rope.",
    "diagnose": "Where simulation and a recording disagree, and the physics left out.",
    "identify": "The loop's shape table from photos of the flying rope.",
}


class PluginUnavailable(RoboWranglerError):
    """A verb of another distribution was asked for and that distribution is not installed (or failed to load)."""


@dataclass(frozen=True)
class LoadedPlugins:
    commands: tuple[click.Command, ...]
    problems: tuple[str, ...]  # one line per entry point that failed to load: "name (dist): error"


def load_plugins(group: str = ENTRY_POINT_GROUP) -> LoadedPlugins:
    """Every command the installed distributions register under `group`; a failing entry point is reported,
    not raised, so that a broken simulator install never takes the board commands down with it."""
    commands: list[click.Command] = []
    problems: list[str] = []
    for ep in metadata.entry_points(group=group):
        dist = ep.dist.name if ep.dist is not None else "?"
        try:
            provided = ep.load()()
            for command in provided:
                if not isinstance(command, click.Command):
                    raise TypeError(f"expected click commands, got {type(command).__name__}")
                commands.append(command)
        except Exception as exc:  # noqa: BLE001 - reported on use of the verb, with the cause
            problems.append(f"{ep.name} ({dist}): {type(exc).__name__}: {exc}")
    return LoadedPlugins(tuple(commands), tuple(problems))


def missing_verb(name: str, problems: tuple[str, ...]) -> click.Command:
    """A stand-in for a simulator verb whose distribution is absent: any use says what to install."""
    summary = SIMULATOR_VERBS[name]

    @click.command(name, help=f"{summary} [needs {SIMULATOR_DISTRIBUTION}]", short_help=f"{summary} [needs "
                   f"{SIMULATOR_DISTRIBUTION}]", context_settings={"ignore_unknown_options": True,
                                                                     "allow_extra_args": True},
                   add_help_option=False)
    def command() -> None:
        if problems:
            raise PluginUnavailable(f"`wrangler {name}` comes from {SIMULATOR_DISTRIBUTION}, which is installed but "
                                    f"failed to load: {'; '.join(problems)}")
        raise PluginUnavailable(f"`wrangler {name}` is part of the simulator, which is not installed here: add the "
                                f"{SIMULATOR_DISTRIBUTION} distribution (from this repository: `uv sync` at its root, "
                                f"or `pip install ./sim` in your environment)")

    return command
