"""The `wrangler` CLI and the Python client against the SIL device, in real time over UDP.

The CLI cannot tell the SIL from the board: these are the commands a user types.
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.client import Client
from robowrangler.errors import CommandRefused
from robowrangler.protocol.generated import NackReason, State
from robowrangler_sim.sil import SilSession


@pytest.fixture
def live_sil(native_build_dir: Path) -> Iterator[SilSession]:
    with SilSession(speedup=1.0) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)  # past the ESC arming hold
        yield sil


def write_key_file(path: Path, key: bytes) -> Path:
    path.write_text(key.hex() + "\n")
    path.chmod(0o600)
    return path


def wrangler(sil: SilSession, *argv: str) -> tuple[ExitStatus, list[dict], str]:
    out, err = io.StringIO(), io.StringIO()
    key_file = write_key_file(Path(sil.state_file).with_name("link.key"), sil.key)
    status = main(["--url", sil.cmd_url, "--key-file", str(key_file), "--json", *argv], Environment(out, err, {}))
    lines = [json.loads(line) for line in out.getvalue().splitlines() if line.strip()]
    return status, lines, err.getvalue()


def test_cli_arms_spins_holds_and_lands_the_rope(live_sil: SilSession) -> None:
    status, out, _ = wrangler(live_sil, "arm")
    assert status == ExitStatus.OK and out[-1]["state"] == "ARMED"
    status, out, err = wrangler(live_sil, "spin", "4", "--hold", "1.5")
    assert status == ExitStatus.OK, err
    airborne = [line for line in out if line.get("state") == "AIRBORNE"]
    assert airborne and abs(airborne[-1]["rope_speed_mps"] - 4.0) < 0.08
    assert out[-1]["type"] == "result" and out[-1]["state"] == "ARMED"  # --hold ends with a spin-down
    assert live_sil.plant.rope_speed_mps < 0.2
    status, out, _ = wrangler(live_sil, "disarm")
    assert status == ExitStatus.OK and out[-1]["state"] == "DISARMED"


def test_cli_refusals_exit_with_the_nack_status_and_reason(live_sil: SilSession) -> None:
    status, out, err = wrangler(live_sil, "spin", "4")  # DISARMED: the device refuses
    assert status == ExitStatus.NACK and out[-1]["reason"] == "BAD_STATE" and "BAD_STATE" in err
    status, out, _ = wrangler(live_sil, "param", "set", "speed_kp", "7")
    assert status == ExitStatus.NACK and out[-1]["reason"] == "OUT_OF_RANGE"
    status, out, _ = wrangler(live_sil, "param", "get", "tov_mps")
    assert status == ExitStatus.OK and out[-1]["value"] == pytest.approx(2.6)


def test_cli_times_out_cleanly_when_no_device_answers(native_build_dir: Path, tmp_path: Path) -> None:
    out, err = io.StringIO(), io.StringIO()
    key_file = write_key_file(tmp_path / "link.key", bytes(range(16)))
    status = main(["--url", "udp://127.0.0.1:9", "--key-file", str(key_file), "--timeout", "0.5", "status"],
                  Environment(out, err, {}))
    assert status == ExitStatus.LINK_TIMEOUT
    assert "udp://127.0.0.1:9" in err.getvalue() and err.getvalue().count("\n") == 1


def test_client_guard_refusal_names_the_guard_and_keeps_flying(live_sil: SilSession) -> None:
    with Client(live_sil.cmd_url, key=live_sil.key) as rw:
        rw.arm(timeout_s=2.0)
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
        with pytest.raises(CommandRefused) as refused:
            rw.spin(2.0)
        assert refused.value.reason == NackReason.BELOW_TOV_GUARD
        assert "2.99" in str(refused.value)
        assert rw.latest_telemetry.state == State.AIRBORNE
        rw.spindown()
        rw.wait_for_state(State.ARMED, timeout_s=5.0)
