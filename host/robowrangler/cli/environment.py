"""Where the CLI writes and reads: injected so that tests run `main(argv, env)` in-process."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TextIO


@dataclass
class Environment:
    """Streams and environment variables of one CLI run.

    stdout: machine output with --json (one JSON object, or JSON lines for streams), else human output.
    stderr: prose, progress and error messages.
    environ: environment variables (ROBOWRANGLER_URL).
    """

    stdout: TextIO = field(default_factory=lambda: sys.stdout)
    stderr: TextIO = field(default_factory=lambda: sys.stderr)
    environ: Mapping[str, str] = field(default_factory=lambda: os.environ)

    @classmethod
    def from_process(cls) -> Environment:
        return cls(sys.stdout, sys.stderr, os.environ)
