"""rw_wifi_supervisor: the board's WiFi connection policy, which the background loop asks what to do.

What must hold: no call into WiFiNINA while the module's ready line is busy (each one would wait for it
without a time limit); a line busy for module_hung_ms is NO_MODULE for good; a loss closes the socket at
once; new connections and opening the socket wait until the rope is down (counted once per deferral);
status polls every status_poll_ms, new attempts at most every reconnect_interval_ms.
"""

from __future__ import annotations

from board_io_ctypes import WifiAction, WifiState, WifiSupervisor

POLL_MS = 500
RECONNECT_MS = 5000
HUNG_MS = 1000


def make(rw_core, state: WifiState, now_ms: int = 0) -> WifiSupervisor:
    return WifiSupervisor(rw_core, state=state, now_ms=now_ms, status_poll_ms=POLL_MS,
                          reconnect_interval_ms=RECONNECT_MS, module_hung_ms=HUNG_MS)


def run(s: WifiSupervisor, start_ms: int, end_ms: int, *, connected: bool, rope_down: bool,
        ready: bool = True, opened: bool = True) -> list[tuple[int, WifiAction]]:
    """Background passes every millisecond; answers polls with `connected`, socket opens with `opened`."""
    actions = []
    for t in range(start_ms, end_ms):
        a = s.step(t & 0xFFFF_FFFF, module_ready=ready, rope_down=rope_down)
        if a == WifiAction.POLL_STATUS:
            s.status(t & 0xFFFF_FFFF, connected=connected)
        elif a == WifiAction.OPEN_SOCKET:
            s.socket(opened=opened)
        if a not in (WifiAction.NOTHING, WifiAction.IO):
            actions.append((t - start_ms, a))
    return actions


def test_up_polls_every_period_and_otherwise_moves_datagrams(rw_core) -> None:
    s = make(rw_core, WifiState.UP)
    assert s.step(1) == WifiAction.IO
    actions = run(s, 1, 2001, connected=True, rope_down=False)
    assert [a for _, a in actions] == [WifiAction.POLL_STATUS] * 4
    assert s.state == WifiState.UP and s.counters.polls == 4


def test_a_loss_in_flight_closes_at_once_and_reconnects_only_once_the_rope_is_down(rw_core) -> None:
    s = make(rw_core, WifiState.UP)
    actions = run(s, 0, 3100, connected=False, rope_down=False)
    assert actions[:2] == [(500, WifiAction.POLL_STATUS), (501, WifiAction.CLOSE_SOCKET)]
    assert WifiAction.START_CONNECT not in [a for _, a in actions], "no connection step while the rope is up"
    assert s.state == WifiState.CONNECTING and s.counters.losses == 1 and s.counters.deferred == 1
    actions = run(s, 3100, 3110, connected=False, rope_down=True)
    assert actions == [(0, WifiAction.START_CONNECT)], "the deferred reconnect runs as soon as the rope is down"
    assert s.counters.deferred == 1


def test_an_association_in_flight_opens_the_socket_only_once_the_rope_is_down(rw_core) -> None:
    s = make(rw_core, WifiState.CONNECTING)
    actions = run(s, 0, 2100, connected=True, rope_down=False)  # the module reconnected by itself
    assert WifiAction.OPEN_SOCKET not in [a for _, a in actions] and s.state == WifiState.CONNECTING
    actions = run(s, 2100, 2102, connected=True, rope_down=True)
    assert (0, WifiAction.OPEN_SOCKET) in actions and s.state == WifiState.UP and s.counters.connects == 1


def test_a_failed_attempt_is_retried_at_the_reconnect_interval(rw_core) -> None:
    s = make(rw_core, WifiState.CONNECTING)
    actions = run(s, 0, 12001, connected=False, rope_down=True)
    starts = [t for t, a in actions if a == WifiAction.START_CONNECT]
    assert starts == [5001, 10001]  # one action a pass: the poll due at 5000 goes first


def test_a_socket_that_does_not_open_is_tried_again_after_the_next_poll(rw_core) -> None:
    s = make(rw_core, WifiState.CONNECTING)
    actions = run(s, 0, 1200, connected=True, rope_down=True, opened=False)
    opens = [t for t, a in actions if a == WifiAction.OPEN_SOCKET]
    assert opens == [501, 1001] and s.state == WifiState.CONNECTING


def test_a_busy_ready_line_means_no_call_and_after_module_hung_ms_no_module(rw_core) -> None:
    s = make(rw_core, WifiState.UP)
    assert run(s, 0, HUNG_MS - 1, connected=True, rope_down=True, ready=False) == []
    assert s.state == WifiState.UP and s.counters.module_busy == HUNG_MS - 1
    assert s.step(HUNG_MS - 1, module_ready=True) == WifiAction.POLL_STATUS  # it answered in time
    s.status(HUNG_MS - 1, connected=True)
    assert run(s, HUNG_MS, 2 * HUNG_MS + 1, connected=True, rope_down=True, ready=False) == []
    assert s.state == WifiState.NO_MODULE and s.counters.module_hangs == 1
    assert run(s, 3000, 20000, connected=True, rope_down=True) == [], "NO_MODULE stays until a reset"


def test_not_provisioned_stays_down_until_credentials_arrive(rw_core) -> None:
    s = make(rw_core, WifiState.NOT_PROVISIONED)
    assert run(s, 0, 6000, connected=True, rope_down=True) == []
    s.restart(6000, provisioned=True)
    assert s.state == WifiState.CONNECTING and s.counters.attempts == 1
    assert (0, WifiAction.POLL_STATUS) in [(t - 500, a) for t, a in run(s, 6000, 6600, connected=True, rope_down=True)]


def test_times_wrap_around_2_to_the_32_ms(rw_core) -> None:
    start = 0xFFFF_FFFF - 700
    s = make(rw_core, WifiState.UP, now_ms=start)
    actions = run(s, start, start + 1200, connected=True, rope_down=True)
    assert [t for t, _ in actions] == [500, 1000]
