"""The simulator's verbs of `wrangler`, registered as plugins through the entry point group `robowrangler.cli`
(sim/pyproject.toml): the host distribution loads them when this one is installed and never imports it otherwise.

Adding a verb: write robowrangler_sim/cli/<verb>.py with a click command and append it in commands() below.
The modules are imported lazily so that `wrangler --help` on a board-only workflow stays quick.
"""

from __future__ import annotations

import click


def commands() -> list[click.Command]:
    """The click commands this distribution adds to `wrangler` (the entry point's target)."""
    from robowrangler_sim.cli import diagnose, identify, sil

    return [sil.sil_command, sil.demo_command, diagnose.diagnose_command, identify.identify_command]
