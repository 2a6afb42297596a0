"""A busy machine slows the SIL down, it does not end it or spin the rope down.

- The lockstep waits for a firmware that is alive but not scheduled (here: stopped with SIGSTOP for several
  tick timeouts, the deterministic form of a machine at load 7-13 on 2 cores) and the run is the same as an
  undisturbed one; a firmware that exited is reported at once.
- A paced SIL whose host is slow (its heartbeat thread far slower than the device's heartbeat timeout, or
  CPU hogs beside it) keeps the rope up: the client keeps its heartbeats on the device's clock and the
  pacing yields instead of racing.
Assertions are on outcomes (state, events, telemetry), never on wall times.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from pathlib import Path

import pytest

from robowrangler.client import Client
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import Cause, EventKind, State
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.errors import SilFirmwareError
from robowrangler_sim.sil.scripted_host import ScriptedHost

KEY = bytes(range(0x20, 0x30))


def spin_run(*, stall_firmware_s: float = 0.0) -> list[gen.Telemetry]:
    """ARM, spin to 4 m/s, run 0.4 s; the firmware stopped for stall_firmware_s (wall) in the middle. Telemetry."""
    with SilSession(speedup=None, key=KEY, tick_timeout_s=0.1) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        host.arm_and_spin(4000, settle_s=0.2)
        if stall_firmware_s:
            os.kill(sil.firmware_pid, signal.SIGSTOP)
            threading.Timer(stall_firmware_s, os.kill, (sil.firmware_pid, signal.SIGCONT)).start()
        host.run_for(0.4)
        slow_ticks = sil.lockstep.slow_ticks
        host.close()
    assert slow_ticks == (1 if stall_firmware_s else 0)
    return host.received.telemetry


def test_a_firmware_that_is_not_scheduled_for_many_tick_timeouts_is_waited_for(native_build_dir: Path) -> None:
    undisturbed = spin_run()
    stalled = spin_run(stall_firmware_s=0.6)  # six tick timeouts
    assert stalled == undisturbed  # the same run: the plant owns the clock, the stall only took wall time
    assert stalled[-1].state == State.AIRBORNE


def test_a_firmware_that_exited_is_reported_at_once(native_build_dir: Path) -> None:
    with SilSession(speedup=None, key=KEY, tick_timeout_s=0.1) as sil:
        sil.step()
        os.kill(sil.firmware_pid, signal.SIGKILL)
        with pytest.raises(SilFirmwareError, match="exited"):
            sil.step()


def heartbeat_losses(client: Client) -> list:
    return [e for e in client.events if e.kind == EventKind.STATE_CHANGED and e.cause == Cause.HEARTBEAT_LOST]


class StalledHeartbeats(Client):
    """A host whose heartbeat thread sends one heartbeat (the device then knows where to send telemetry) and is
    never scheduled again: the extreme of a thread starved on a busy machine."""

    def _heartbeat_loop(self) -> None:
        self._send_new(gen.Heartbeat(0))
        self._stop.wait()


def hold_airborne(sil: SilSession, *, hold_device_s: float, client: type[Client] = Client) -> tuple[Client, object]:
    with client(sil.cmd_url, key=sil.key, connect_timeout_s=5.0) as rw:
        rw.arm(timeout_s=5.0)
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=10.0)
        start_s = rw.latest_telemetry.time_s
        last = rw.wait_for(lambda s: s.time_s - start_s >= hold_device_s, timeout_s=30.0)
        rw.spindown()
    return rw, last


def test_a_host_whose_heartbeat_thread_stalls_does_not_spin_a_paced_sil_down(native_build_dir: Path) -> None:
    """Only the client's receiver runs; the device's telemetry says when it has heard nothing for a heartbeat
    period of its own clock, and the receiver answers with a heartbeat."""
    with SilSession(speedup=3.0, key=KEY) as sil:
        sil.run_in_background()
        rw, last = hold_airborne(sil, hold_device_s=3.0, client=StalledHeartbeats)  # six heartbeat timeouts
        sil.check()
    assert last.state == State.AIRBORNE and heartbeat_losses(rw) == []
    assert rw.stats.device_clock_heartbeats >= 3.0 * rw.heartbeat_hz / 2


def _hog(stop_at: float) -> None:
    while time.monotonic() < stop_at:
        pass


def test_a_paced_sil_keeps_the_rope_up_beside_cpu_hogs(native_build_dir: Path) -> None:
    """Two busy processes on the two cores (a loaded machine) while a SIL paced at 3x holds the rope airborne."""
    stop_at = time.monotonic() + 30.0
    hogs = [multiprocessing.Process(target=_hog, args=(stop_at,), daemon=True) for _ in range(2)]
    for h in hogs:
        h.start()
    try:
        with SilSession(speedup=3.0, key=KEY) as sil:
            sil.run_in_background()
            rw, last = hold_airborne(sil, hold_device_s=2.0)
            sil.check()
    finally:
        for h in hogs:
            h.terminate()
            h.join()
    assert last.state == State.AIRBORNE and heartbeat_losses(rw) == []
