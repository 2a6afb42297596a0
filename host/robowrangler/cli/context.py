"""What every command gets: the link settings from the global options and the output channel."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import click

from robowrangler.cli.environment import Environment
from robowrangler.client import Client
from robowrangler.errors import InvalidArgument
from robowrangler.protocol.generated import KEY_LEN

URL_ENV_VAR = "ROBOWRANGLER_URL"
KEY_FILE_ENV_VAR = "ROBOWRANGLER_KEY_FILE"
DEFAULT_TIMEOUT_S = 3.0


class OutputClosed(Exception):
    """stdout was closed by its reader (`wrangler watch --json | head`): stop quietly, exit OK.

    Deliberately not an OSError, so that click does not turn it into its own exit."""


@dataclass
class CliContext:
    """Global options of one `wrangler` run plus its Environment.

    url: link URL (--url, else $ROBOWRANGLER_URL, else the default); timeout_s: --timeout [s], used
    as the connect timeout, the longest telemetry gap and the ARM NOT_READY retry window;
    json_mode: --json.
    """

    env: Environment
    url: str
    timeout_s: float = DEFAULT_TIMEOUT_S
    json_mode: bool = False
    key: bytes | None = field(default=None, repr=False)  # the link key: never printed

    def client(self) -> Client:
        """A Client for this run's URL (not yet connected: use it in a `with`)."""
        return Client(self.url, connect_timeout_s=self.timeout_s, key=self.key)

    # -- output: machine output on stdout only with --json, prose on stderr
    def result(self, data: dict[str, Any], human: str) -> None:
        """The final result: one JSON object (ok: true) on stdout with --json, else `human` on stdout."""
        if self.json_mode:
            self.json_line({"type": "result", "ok": True, **data})
        else:
            self._write(human.rstrip("\n") + "\n")

    def json_line(self, data: dict[str, Any]) -> None:
        """One JSON object on one line of stdout (JSON lines for streams)."""
        self._write(json.dumps(_jsonable(data), allow_nan=False) + "\n")

    def human_line(self, text: str) -> None:
        """A line of human stream output on stdout (not used with --json)."""
        self._write(text + "\n")

    def _write(self, text: str) -> None:
        try:
            self.env.stdout.write(text)
            self.env.stdout.flush()
        except BrokenPipeError:
            raise OutputClosed from None

    def note(self, text: str) -> None:
        """Prose for the user on stderr (both modes)."""
        self.env.stderr.write(f"wrangler: {text}\n")
        self.env.stderr.flush()


class Seconds(click.FloatRange):
    """A duration in seconds on the command line: a finite number >= 0 (> 0 with positive=True).

    click's FloatRange lets NaN through (every comparison with NaN is false): `record --duration nan`
    would run forever. NaN and inf are refused here as usage errors, as the motion arguments are."""

    name = "seconds"

    def __init__(self, *, positive: bool = False) -> None:
        super().__init__(min=0.0, min_open=positive)

    def convert(self, value, param, ctx):  # noqa: ANN001 - click's signature
        x = click.FLOAT.convert(value, param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number of seconds.", param, ctx)
        return super().convert(x, param, ctx)


def read_key_file(path: str) -> bytes:
    """The link key from a file holding it as 32 hex digits (whitespace ignored). The key is never echoed:
    errors name the file and what is wrong with it, not its content."""
    try:
        text = Path(path).read_text()
    except OSError as err:
        raise InvalidArgument("--key-file", "a readable file with the link key", f"{path} ({err.strerror})") from None
    digits = "".join(text.split())
    try:
        key = bytes.fromhex(digits)
    except ValueError:
        key = b""
    if len(key) != KEY_LEN:
        raise InvalidArgument("--key-file", f"{2 * KEY_LEN} hex digits", f"{path} with {len(digits)} characters")
    return key


def _jsonable(value: Any) -> Any:
    """JSON-safe copy: non-finite floats become null (JSON has no NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return value


pass_context = click.make_pass_decorator(CliContext)
