"""`wrangler` as a new user meets it (issue 18): first commands on a fresh HOME, bad numbers, no subcommand,
--version, `help CMD`, --json after the verb. In-process through main(argv, env), against the scripted device."""

from __future__ import annotations

import pytest

from robowrangler.cli.exit_status import ExitStatus
from scripted_device import ScriptedDevice
from test_cli import wrangler


def test_keygen_creates_the_missing_config_folder_privately(tmp_path) -> None:
    path = tmp_path / "home" / ".config" / "robowrangler" / "link.key"
    run = wrangler("keygen", str(path))
    assert run.status == ExitStatus.OK, run.stderr
    assert len(bytes.fromhex(path.read_text().strip())) == 16
    assert oct(path.stat().st_mode & 0o777) == "0o600" and oct(path.parent.stat().st_mode & 0o777) == "0o700"
    again = wrangler("keygen", str(path))
    assert again.status == ExitStatus.USAGE and again.stderr.startswith("wrangler: PATH: expected a path that does "
                                                                         "not exist yet")


def test_keygen_errors_name_the_argument_the_user_typed(tmp_path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    run = wrangler("keygen", str(blocker / "link.key"))
    assert run.status == ExitStatus.USAGE and run.stderr.startswith("wrangler: PATH: ")
    assert "--generate-key" not in run.stderr and str(blocker) in run.stderr


@pytest.mark.parametrize("argv, expected", [
    (["spin", "1e308"], "MPS: expected a speed encodable as int32 mm/s"),
    (["spin", "--", "-1e308"], "MPS: expected a speed encodable as int32 mm/s"),
    (["loop", "1e308"], "GUIDE_MM: expected a guide position encodable on the wire (|x| <= 2147483.647 mm)"),
    (["loop", "1e9"], "(|x| <= 2147483.647 mm), got 1000000000.0"),
    (["spin", "2", "--hold", "nan"], "'nan' is not a finite number of seconds"),
    (["loop", "50", "--within", "nan"], "'nan' is not a finite number of seconds"),
    (["watch", "--duration", "inf"], "'inf' is not a finite number of seconds"),
    (["param", "set", "encoder_counts_per_rev", "64.5"], "encoder_counts_per_rev: expected an integer"),
])
def test_numbers_nothing_can_carry_are_usage_errors_before_the_link(argv: list[str], expected: str) -> None:
    with ScriptedDevice() as dev:
        run = wrangler("--url", dev.url, *argv)
        assert dev.received == []
    assert run.status == ExitStatus.USAGE and expected in run.stderr, run.stderr
    assert run.stderr.count("\n") == 1 and "internal error" not in run.stderr


@pytest.mark.parametrize("argv, usage", [([], "wrangler [OPTIONS] COMMAND"), (["param"], "wrangler param [OPTIONS]"),
                                         (["provision"], "wrangler provision [OPTIONS]")])
def test_no_subcommand_prints_the_help_as_help_not_one_line(argv: list[str], usage: str) -> None:
    run = wrangler(*argv)
    assert run.status == ExitStatus.USAGE and run.stdout == ""
    lines = run.stderr.splitlines()
    assert lines[0] == f"Usage: {usage} COMMAND [ARGS]..." if argv else lines[0].startswith(f"Usage: {usage}")
    assert len(lines) > 8 and "Commands:" in run.stderr
    assert lines[-1].startswith("wrangler: missing command")


def test_version_and_help_command() -> None:
    version = wrangler("--version")
    assert version.status == ExitStatus.OK and version.stdout.startswith("wrangler 0.") and "protocol v2" in version.stdout
    helped = wrangler("help", "param", "set")
    assert helped.status == ExitStatus.OK and helped.stdout == wrangler("param", "set", "--help").stdout
    assert wrangler("help").stdout == wrangler("--help").stdout
    unknown = wrangler("help", "fly")
    assert unknown.status == ExitStatus.USAGE and "No such command 'fly'" in unknown.stderr


@pytest.mark.parametrize("argv", [["status", "--json"], ["watch", "--duration", "0.1", "--json"],
                                  ["param", "get", "tov_mps", "--json"], ["arm", "--json"]])
def test_json_works_after_any_verb(device: ScriptedDevice, argv: list[str]) -> None:
    run = wrangler("--url", device.url, *argv)
    assert run.status == ExitStatus.OK, run.stderr
    assert run.json_lines and all(isinstance(line, dict) for line in run.json_lines)
