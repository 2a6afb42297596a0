"""Key handling end to end: keygen, provisioning over the device's USB serial, commands over UDP, wrong keys."""

from __future__ import annotations

import io
import json
import stat
from collections.abc import Iterator
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.scripted_host import ScriptedHost


def run(*argv: str) -> tuple[ExitStatus, list[dict], str]:
    out, err = io.StringIO(), io.StringIO()
    status = main(["--json", *argv], Environment(out, err, {}))
    return status, [json.loads(x) for x in out.getvalue().splitlines() if x.strip()], err.getvalue()


@pytest.fixture
def blank_sil(native_build_dir: Path, tmp_path: Path) -> Iterator[SilSession]:
    """A live SIL device never provisioned, as a board out of the box (its flash: a file)."""
    with SilSession(speedup=1.0, provision=False, state_file=tmp_path / "flash.bin") as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        yield sil


def test_keygen_writes_a_private_key_and_never_overwrites_it(tmp_path: Path) -> None:
    path = tmp_path / "link.key"
    status, out, err = run("keygen", str(path))
    key = path.read_text().strip()
    assert status == ExitStatus.OK and out[-1]["key_file"] == str(path) and len(bytes.fromhex(key)) == 16
    assert stat.S_IMODE(path.stat().st_mode) == 0o600 and key not in json.dumps(out) + err
    assert run("keygen", str(path))[0] == ExitStatus.USAGE and path.read_text().strip() == key


def test_provision_over_usb_then_command_over_udp(blank_sil: SilSession, tmp_path: Path) -> None:
    key_file = tmp_path / "link.key"
    run("keygen", str(key_file))
    udp = ["--url", blank_sil.cmd_url, "--key-file", str(key_file), "--timeout", "1"]
    status, _, err = run(*udp, "arm")
    assert status == ExitStatus.AUTH and "provision" in err  # no key on the device yet: it takes nothing
    status, out, err = run("provision", "--port", blank_sil.serial_path, "set",
                           "--link-key-file", str(key_file), "--wifi-ssid", "lab")
    assert status == ExitStatus.OK, err
    assert out[-1]["key_set"] and out[-1]["wifi_ssid"] == "lab"
    status, _, err = run(*udp, "arm")
    assert status == ExitStatus.OK, err


def test_a_wrong_key_is_named_as_such(blank_sil: SilSession, tmp_path: Path) -> None:
    good, bad = tmp_path / "good.key", tmp_path / "bad.key"
    run("keygen", str(good))
    run("keygen", str(bad))
    serial = f"serial://{blank_sil.serial_path}"
    assert run("--url", serial, "provision", "set", "--link-key-file", str(good))[0] == ExitStatus.OK
    status, _, err = run("--url", blank_sil.cmd_url, "--key-file", str(bad), "--timeout", "1", "status")
    assert status == ExitStatus.AUTH and "key" in err and err.count("\n") == 1
    assert run("--url", blank_sil.cmd_url, "--key-file", str(good), "--timeout", "1", "status")[0] == ExitStatus.OK


def test_provisioning_is_refused_over_wifi(native_build_dir: Path) -> None:
    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.1)
        nack = host.command(gen.ProvisionSetKey(bytes(16)))  # even correctly signed
        assert isinstance(nack, gen.Nack) and nack.reason == gen.NackReason.NOT_ON_THIS_LINK
        host.close()
