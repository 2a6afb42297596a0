"""Fixtures for the network-impairment and plant-fault suites: SIL sessions behind an ImpairmentProxy."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import ExitStack
from pathlib import Path

import pytest

from robowrangler.protocol.generated import State
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.impairment import ImpairedLockstep, ImpairmentConfig, ImpairmentProxy
from robowrangler_sim.sil.scripted_host import ScriptedHost

# link_gate, link_ledger and soak_runner are imported by plain name from the tests of this folder and from
# bench/bench_soak.py (also under pytest's importlib mode, where test folders are not on sys.path).
_HERE = str(Path(__file__).resolve().parent)
if _HERE not in sys.path:
    sys.path.insert(0, _HERE)
from link_gate import seeded_key  # noqa: E402


@pytest.fixture
def lossy_host(native_build_dir: Path) -> Iterator[Callable[..., ScriptedHost]]:
    """Factory: a ScriptedHost talking through an ImpairmentProxy (lockstep, deterministic) to an unpaced SIL.

    lossy_host(config, seed=0, warmup_s=0.6) -> host; host.sil.proxy is the proxy (logging on), host.sil.sil
    the SilSession, host.key (= host.sil.key) its link key, derived from the seed (same seed, same bytes).
    The impairment starts after the warm-up (past the ESC arming hold), with a clean link before it.
    """
    with ExitStack() as stack:
        def make(config: ImpairmentConfig, *, seed: int = 0, warmup_s: float = 0.6) -> ScriptedHost:
            sil = stack.enter_context(SilSession(speedup=None, seed=seed, key=seeded_key(seed)))
            proxy = stack.enter_context(ImpairmentProxy(device_port=sil.cmd_port, seed=seed, keep_log=True))
            host = ScriptedHost(ImpairedLockstep(sil, proxy))
            stack.callback(host.close)
            host.run_for(warmup_s)
            proxy.config = config
            return host
        yield make


@pytest.fixture
def plain_host(native_build_dir: Path) -> Iterator[ScriptedHost]:
    """A scripted host on an unpaced SIL without a proxy, past the ESC arming hold (0.6 s simulated)."""
    with SilSession(speedup=None, key=seeded_key(0)) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        yield host
        host.close()



FLYING_MMPS = 5000  # the rope speed of the `flying` fixture


@pytest.fixture
def flying(native_build_dir: Path) -> Iterator[ScriptedHost]:
    """Rope airborne at FLYING_MMPS (5 m/s) and settled (2.6 s simulated), every tick traced."""
    with SilSession(speedup=None, trace_every=1) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        host.arm_and_spin(FLYING_MMPS, settle_s=1.5)
        assert host.last_telemetry.state == State.AIRBORNE
        yield host
        host.close()
