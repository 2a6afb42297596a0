"""`wrangler`: command the RoboWrangler device (board or SIL) from a shell.

main(argv, env) is the one place where exceptions become exit statuses (ExitStatus) and one-line
messages on stderr; with --json the same failure is also one JSON object on stdout.

Adding a command group: write robowrangler/cli/<group>.py with click commands and append them to
COMMANDS below. Verbs of other distributions (the simulator's sil, demo, diagnose, identify) arrive as plugins
(robowrangler/cli/plugins.py); the host never imports them.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Sequence
from typing import Any

import click

from robowrangler.cli import excite, monitor, motion, param, plugins, provision, proxy, record, spindle
from robowrangler.cli.context import (DEFAULT_TIMEOUT_S, KEY_FILE_ENV_VAR, URL_ENV_VAR, CliContext, OutputClosed,
                                      Seconds, read_key_file)
from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.protocol.generated import PROTOCOL_VERSION
from robowrangler.errors import (AuthenticationError, CommandRefused, InvalidArgument, LinkTimeout, RoboWranglerError,
                                 UnknownParameter)
from robowrangler.transport import DEFAULT_URL, parse_url

COMMANDS: list[click.Command] = [
    motion.arm, motion.disarm, motion.spin, motion.spindown, motion.estop,
    spindle.home, spindle.loop, spindle.relax, spindle.retract, spindle.grasp, spindle.release,
    monitor.status, monitor.watch,
    param.param, provision.provision, provision.keygen,
    record.record, record.inspect, record.replay, proxy.proxy,
    excite.excite,
]

_EXIT_HELP = "Exit status: " + ", ".join(f"{s.value} {s.name}" for s in ExitStatus) + "."


@click.group(epilog=_EXIT_HELP)
@click.version_option(package_name="robowrangler", prog_name="wrangler",
                      message="%(prog)s %(version)s (protocol v" + str(PROTOCOL_VERSION) + ")")
@click.option("--url", default=None, metavar="URL",
              help=f"Link: udp://HOST:PORT or serial:///dev/ttyACM0?baud=115200 "
                   f"[env {URL_ENV_VAR}; default {DEFAULT_URL}]")
@click.option("--json", "json_mode", is_flag=True, help="Machine output on stdout: one JSON object, JSON lines for streams.")
@click.option("--timeout", "timeout_s", type=Seconds(positive=True), default=DEFAULT_TIMEOUT_S,
              show_default=True, metavar="SECONDS",
              help="Connect timeout, longest telemetry gap, and ARM retry window.")
@click.option("--key-file", "key_file", default=None, metavar="PATH",
              help=f"File with the 128-bit link key (32 hex digits) for signed frames [env {KEY_FILE_ENV_VAR}; "
                   "default: unsigned frames].")
@click.pass_context
def cli(click_ctx: click.Context, url: str | None, json_mode: bool, timeout_s: float, key_file: str | None) -> None:
    """Command a RoboWrangler rope lasso (board or SIL) over UDP or USB serial."""
    env: Environment = click_ctx.obj
    url = url or env.environ.get(URL_ENV_VAR) or DEFAULT_URL
    parse_url(url)  # a malformed URL is a usage error before anything is opened
    key_file = key_file or env.environ.get(KEY_FILE_ENV_VAR)
    key = read_key_file(key_file) if key_file else None
    click_ctx.obj = CliContext(env=env, url=url, timeout_s=timeout_s, json_mode=json_mode, key=key)


@click.command("help")
@click.argument("command_path", nargs=-1, metavar="[COMMAND]...")
@click.pass_context
def help_command(click_ctx: click.Context, command_path: tuple[str, ...]) -> None:
    """Show the help of COMMAND (`wrangler help param set`), or of wrangler itself."""
    root = click_ctx.find_root()
    command: click.Command = root.command
    ctx = root
    for name in command_path:
        sub = command.get_command(ctx, name) if isinstance(command, click.Group) else None
        if sub is None:
            raise click.UsageError(f"No such command {' '.join(command_path)!r}", ctx=click_ctx)
        ctx = click.Context(sub, info_name=name, parent=ctx)
        command = sub
    click.echo(command.get_help(ctx))


for _command in [*COMMANDS, help_command]:
    cli.add_command(_command)

_plugins_installed = False


def _install_plugins() -> None:
    """Add the verbs other installed distributions register (once, at the first main()), and a stand-in that
    names the missing distribution for each simulator verb none provided."""
    global _plugins_installed
    if _plugins_installed:
        return
    _plugins_installed = True
    loaded = plugins.load_plugins()
    for command in loaded.commands:
        if command.name in cli.commands:
            raise RuntimeError(f"plugin verb {command.name!r} clashes with a built-in wrangler command")
        cli.add_command(command)
    for verb in plugins.SIMULATOR_VERBS:
        if verb not in cli.commands:
            cli.add_command(plugins.missing_verb(verb, loaded.problems))


def _json_first(argv: list[str]) -> list[str]:
    """`--json` anywhere before a `--` means the global --json: `wrangler watch --json` works as
    `wrangler --json watch` does."""
    end = argv.index("--") if "--" in argv else len(argv)
    if "--json" not in argv[:end]:
        return argv
    return ["--json", *(a for a in argv[:end] if a != "--json"), *argv[end:]]


def main(argv: Sequence[str] | None = None, env: Environment | None = None) -> ExitStatus:
    """Run `wrangler` with argv (without the program name); returns the exit status.

    Every exception is turned into an ExitStatus and one line on env.stderr here, and nowhere else.
    """
    env = env or Environment.from_process()
    argv = list(sys.argv[1:] if argv is None else argv)
    argv = _json_first(argv)
    json_mode = argv[:1] == ["--json"]
    try:
        _install_plugins()
        with contextlib.redirect_stdout(env.stdout), contextlib.redirect_stderr(env.stderr):
            rv = cli.main(args=argv, prog_name="wrangler", standalone_mode=False, obj=env)
        # click returns the Exit code for --help and friends, the command's value otherwise
        return ExitStatus(rv) if isinstance(rv, int) and rv in ExitStatus._value2member_map_ else ExitStatus.OK
    except click.exceptions.Exit as exit_:
        return _status_from_code(exit_.exit_code)
    except click.exceptions.NoArgsIsHelpError as err:  # `wrangler`, `wrangler param`: the help, as printed by --help
        env.stderr.write(err.ctx.get_help() + "\n")
        return _fail(env, json_mode, ExitStatus.USAGE, err,
                     f"missing command: `{err.ctx.command_path} COMMAND` (the commands are listed above)")
    except click.UsageError as err:
        hint = f" (see `{err.ctx.command_path} --help`)" if err.ctx is not None else ""
        return _fail(env, json_mode, ExitStatus.USAGE, err, err.format_message() + hint)
    except OutputClosed:  # `wrangler watch --json | head`: the reader has all it wanted
        return ExitStatus.OK
    except SystemExit as exit_:  # click exits by itself on some I/O errors even in non-standalone mode
        return _status_from_code(exit_.code if isinstance(exit_.code, int) else 1)
    except (click.Abort, KeyboardInterrupt) as err:
        return _fail(env, json_mode, ExitStatus.CTRL_C, err, "interrupted")
    except (InvalidArgument, UnknownParameter) as err:
        return _fail(env, json_mode, ExitStatus.USAGE, err, str(err))
    except CommandRefused as err:
        return _fail(env, json_mode, ExitStatus.NACK, err, str(err),
                     command=err.command, reason=_name(err.reason), state=_name(err.state), detail=err.detail)
    except LinkTimeout as err:
        return _fail(env, json_mode, ExitStatus.LINK_TIMEOUT, err, str(err), url=err.url, waited_s=err.waited_s)
    except AuthenticationError as err:
        message = str(err)
        if err.needs_key:  # this wrangler has no key: say where it looked and how to get one
            message = (f"{err.url} requires signed frames and no link key was given: wrangler reads the key from "
                       f"--key-file PATH, else from the file ${KEY_FILE_ENV_VAR} names (neither was set). Make a key "
                       "with `wrangler keygen PATH` and provision the device with it over USB (`wrangler provision "
                       "--port /dev/ttyACM0 set --link-key-file PATH`); a `wrangler sil` prints the key file it "
                       f"provisioned (export {KEY_FILE_ENV_VAR}=...)")
        return _fail(env, json_mode, ExitStatus.AUTH, err, message, url=err.url, needs_key=err.needs_key)
    except RoboWranglerError as err:
        return _fail(env, json_mode, ExitStatus.ERROR, err, str(err))
    except OSError as err:
        return _fail(env, json_mode, ExitStatus.ERROR, err, f"link error: {err}")
    except Exception as err:  # noqa: BLE001 - the CLI's last line of defence: one line, no traceback
        return _fail(env, json_mode, ExitStatus.ERROR, err, f"internal error: {type(err).__name__}: {err}")


def _fail(env: Environment, json_mode: bool, status: ExitStatus, err: BaseException, message: str,
          **fields: Any) -> ExitStatus:
    """Write the one-line message on stderr (and the JSON error object on stdout with --json)."""
    line = " ".join(message.split())  # one line, whatever the exception text contained
    env.stderr.write(f"wrangler: {line}\n")
    env.stderr.flush()
    if json_mode:
        import json

        obj = {"type": "result", "ok": False, "exit_status": status.name, "exit_code": int(status),
               "error": type(err).__name__, "message": line, **fields}
        env.stdout.write(json.dumps(obj) + "\n")
        env.stdout.flush()
    return status


def _status_from_code(code: int | None) -> ExitStatus:
    try:
        return ExitStatus(code or 0)
    except ValueError:
        return ExitStatus.ERROR


def _name(value: Any) -> Any:
    return getattr(value, "name", value)


def entry_point() -> None:
    """Console script `wrangler` (pyproject [project.scripts])."""
    status = main(sys.argv[1:], Environment.from_process())
    try:
        sys.stdout.flush()
    except BrokenPipeError:  # keep the interpreter from complaining about the closed pipe at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    sys.exit(int(status))
