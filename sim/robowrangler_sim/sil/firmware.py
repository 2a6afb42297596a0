"""The SIL firmware process (``rw_sil``): find it, start it on free ports, stop it.

It prints its ports and the path of the pseudo-terminal that stands in for the board's USB serial; the
state file stands in for the board's flash (configuration record: key, parameters, boot counter).
"""

from __future__ import annotations

import os
import re
import select
import subprocess
from pathlib import Path

from robowrangler_sim.sil.errors import SilFirmwareError

_READY = re.compile(r"rw_sil ready cmd_port=(\d+) plant_port=(\d+) serial=(\S+)")
REPO_ROOT = Path(__file__).resolve().parents[3]


def find_sil_binary() -> Path:
    """The rw_sil executable: $ROBOWRANGLER_SIL_BIN, else build/native/hal/sil/rw_sil in the checkout."""
    env = os.environ.get("ROBOWRANGLER_SIL_BIN")
    candidates = [Path(env)] if env else []
    build_dir = Path(os.environ.get("ROBOWRANGLER_BUILD_DIR", REPO_ROOT / "build" / "native"))
    candidates.append(build_dir / "hal" / "sil" / "rw_sil")
    for path in candidates:
        if path.is_file() and os.access(path, os.X_OK):
            return path
    raise SilFirmwareError(
        f"SIL firmware not found (looked at {', '.join(str(c) for c in candidates)}); build it with "
        "`cmake -S firmware -B build/native && cmake --build build/native` or set ROBOWRANGLER_SIL_BIN"
    )


class FirmwareProcess:
    """``rw_sil`` as a child process. Ports 0 pick free ones; the bound ports are read from its ready line."""

    def __init__(self, *, cmd_port: int = 0, plant_port: int = 0, plant_timeout_s: int = 10, tick_us: int = 1000,
                 state_file: Path | None = None, binary: Path | None = None, start_timeout_s: float = 5.0,
                 spindle_bus_us: int | None = None, wifi_args: list[str] | None = None) -> None:
        for name, port in (("cmd_port", cmd_port), ("plant_port", plant_port)):
            if not isinstance(port, int) or not 0 <= port <= 65535:
                raise ValueError(f"{name}: expected a UDP port 0..65535, got {port!r}")
        self.binary = Path(binary) if binary is not None else find_sil_binary()
        self._args = [str(self.binary), "--cmd-port", str(cmd_port), "--plant-port", str(plant_port),
                      "--plant-timeout-s", str(int(plant_timeout_s)), "--tick-us", str(int(tick_us))]
        if state_file is not None:
            self._args += ["--state-file", str(state_file)]
        if spindle_bus_us is not None:
            if isinstance(spindle_bus_us, bool) or not isinstance(spindle_bus_us, int) or not 1 <= spindle_bus_us <= 1_000_000:
                raise ValueError(f"spindle_bus_us: expected the bus time of one spindle transaction, 1..1000000 us, "
                                 f"got {spindle_bus_us!r}")
            self._args += ["--spindle-bus-us", str(spindle_bus_us)]
        self._args += list(wifi_args or [])  # the NINA module's faults (wifi_module.WifiModule.firmware_args)
        self.exit_stderr = ""  # what the process wrote on stderr, read when it is stopped
        self._start_timeout_s = start_timeout_s
        self._proc: subprocess.Popen[str] | None = None
        self.cmd_port = 0
        self.plant_port = 0
        self.serial_path = ""

    def start(self) -> FirmwareProcess:
        self._proc = subprocess.Popen(self._args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self._proc.stdout], [], [], self._start_timeout_s)
        line = self._proc.stdout.readline() if ready else ""
        match = _READY.search(line)
        if not match:
            err = self._stop_and_read_stderr()  # read before the pipes close: it names the real cause
            raise SilFirmwareError(f"{self.binary} did not start: {(line + err).strip() or 'no output'}")
        self.cmd_port, self.plant_port = int(match.group(1)), int(match.group(2))
        self.serial_path = match.group(3)
        return self

    @property
    def pid(self) -> int | None:
        """The firmware's process id (None before start)."""
        return None if self._proc is None else self._proc.pid

    def poll(self) -> int | None:
        """Exit code if the process has ended, else None."""
        return None if self._proc is None else self._proc.poll()

    def stderr_text(self) -> str:
        if self._proc is None or self._proc.poll() is None or self._proc.stderr is None:
            return ""
        return self._proc.stderr.read()

    def _stop_and_read_stderr(self) -> str:
        """End the process (if still running) and return what it wrote on stderr, then close its pipes."""
        assert self._proc is not None
        if self._proc.poll() is None:
            self._proc.terminate()
        try:
            _, err = self._proc.communicate(timeout=3)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            _, err = self._proc.communicate()
        return err or ""

    def stop(self) -> None:
        if self._proc is None:
            return
        if self._proc.poll() is None:
            self._proc.terminate()
            try:
                self._proc.wait(timeout=3)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
        if self._proc.stderr is not None and not self._proc.stderr.closed:
            self.exit_stderr = self._proc.stderr.read()
        for stream in (self._proc.stdout, self._proc.stderr):
            if stream is not None:
                stream.close()

    def __enter__(self) -> FirmwareProcess:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
