"""Key handling through the CLI: keygen, provisioning over the device's USB serial, a wrong or missing key."""

from __future__ import annotations

import io
import json
import os
import stat
from collections.abc import Iterator
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.link_security import read_key_file, write_key_file
from robowrangler_sim.sil import SilSession


def run(*argv: str, stdin: str = "") -> tuple[ExitStatus, list[dict], str]:
    out, err = io.StringIO(), io.StringIO()
    import sys
    old_stdin, sys.stdin = sys.stdin, io.StringIO(stdin)
    try:
        status = main(["--json", *argv], Environment(out, err, {}))
    finally:
        sys.stdin = old_stdin
    return status, [json.loads(x) for x in out.getvalue().splitlines() if x.strip()], err.getvalue()


@pytest.fixture
def blank_sil(native_build_dir: Path, tmp_path: Path) -> Iterator[SilSession]:
    """A live SIL device that has never been provisioned (as a board out of the box)."""
    with SilSession(speedup=1.0, provision=False, state_file=tmp_path / "flash.bin") as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        yield sil


def test_keygen_writes_a_private_key_file_and_never_prints_the_key(tmp_path: Path) -> None:
    path = tmp_path / "k" / "link.key"
    status, out, err = run("--key-file", str(path), "keygen")
    assert status == ExitStatus.OK and out[-1]["key_file"] == str(path)
    key = read_key_file(path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert key.hex() not in json.dumps(out) + err
    status, _, err = run("--key-file", str(path), "keygen")  # never overwritten by accident
    assert status == ExitStatus.AUTH and "--force" in err and read_key_file(path) == key


def test_provision_over_usb_then_command_over_udp(blank_sil: SilSession, tmp_path: Path) -> None:
    key_file = tmp_path / "link.key"
    run("--key-file", str(key_file), "keygen")
    url = ["--url", blank_sil.cmd_url, "--key-file", str(key_file), "--timeout", "1"]
    status, _, err = run(*url, "arm")
    assert status == ExitStatus.AUTH and "provision" in err  # the device has no key yet
    status, out, _ = run("--key-file", str(key_file), "provision", "--port", blank_sil.serial_path,
                         "--ssid", "lab", "--password-stdin", "--param", "tov_margin=1.2", stdin="correct horse\n")
    assert status == ExitStatus.OK
    assert out[-1]["key_set"] and out[-1]["wifi_ssid"] == "lab" and out[-1]["password_set"]
    status, out, err = run(*url, "arm")
    assert status == ExitStatus.OK, err
    status, out, _ = run(*url, "param", "get", "tov_margin")
    assert out[-1]["value"] == pytest.approx(1.2)


def test_a_wrong_key_is_named_as_such(blank_sil: SilSession, tmp_path: Path) -> None:
    good, bad = tmp_path / "good.key", tmp_path / "bad.key"
    run("--key-file", str(good), "keygen")
    run("--key-file", str(bad), "keygen")
    assert run("--key-file", str(good), "provision", "--port", blank_sil.serial_path)[0] == ExitStatus.OK
    status, _, err = run("--url", blank_sil.cmd_url, "--key-file", str(bad), "--timeout", "1", "status")
    assert status == ExitStatus.AUTH and "does not match" in err and err.count("\n") == 1


def test_a_key_file_others_can_read_is_refused(tmp_path: Path) -> None:
    path = write_key_file(tmp_path / "link.key", bytes(range(16)))
    os.chmod(path, 0o644)
    status, _, err = run("--url", "udp://127.0.0.1:9", "--key-file", str(path), "status")
    assert status == ExitStatus.AUTH and "chmod 600" in err


def test_provisioning_is_refused_over_wifi(native_build_dir: Path) -> None:
    from robowrangler.protocol import generated as gen
    from robowrangler_sim.sil.scripted_host import ScriptedHost

    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.1)
        nack = host.command(gen.ProvisionSetKey(bytes(16)))  # even correctly signed
        assert isinstance(nack, gen.Nack) and nack.reason == gen.NackReason.NOT_ON_THIS_LINK
        host.close()
