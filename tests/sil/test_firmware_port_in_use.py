"""A second SIL firmware on a port already taken says so (the cause is read before its pipes close)."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from robowrangler_sim.sil.errors import SilFirmwareError
from robowrangler_sim.sil.firmware import FirmwareProcess


def test_a_port_in_use_is_named_as_the_cause(native_build_dir: Path) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        with pytest.raises(SilFirmwareError) as err:
            FirmwareProcess(cmd_port=port).start()
    assert f"cannot bind command port 127.0.0.1:{port}" in str(err.value)
    assert "Address already in use" in str(err.value)


def test_a_second_wrangler_sil_on_a_taken_port_names_it(native_build_dir: Path) -> None:
    import io

    from robowrangler.cli.environment import Environment
    from robowrangler.cli.exit_status import ExitStatus
    from robowrangler.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        status = main(["sil", "--port", str(port), "--duration", "1"], Environment(out, err, {}))
    assert status == ExitStatus.ERROR and "internal error" not in err.getvalue()
    assert f"cannot bind command port 127.0.0.1:{port}: Address already in use" in err.getvalue()
