"""rw_link_status: what the board (and the SIL, which uses the same code) shows a person about its WiFi link -
the status LED's pattern per link state and the USB status line."""

from __future__ import annotations

import ctypes

import pytest

from board_io_ctypes import WifiState


@pytest.fixture(scope="module")
def status(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    rw_core.rw_link_status_led_on.restype = ctypes.c_bool
    rw_core.rw_link_status_led_on.argtypes = [ctypes.c_uint32, ctypes.c_uint8]
    rw_core.rw_link_status_text.restype = ctypes.c_char_p
    rw_core.rw_link_status_text.argtypes = [ctypes.c_uint8]
    return rw_core


def _lit(status: ctypes.CDLL, state: int, t0_ms: int, span_ms: int) -> tuple[int, int]:
    """(ms lit, switches) over [t0, t0 + span)."""
    seq = [bool(status.rw_link_status_led_on((t0_ms + i) & 0xFFFF_FFFF, state)) for i in range(span_ms)]
    return sum(seq), sum(a != b for a, b in zip(seq, seq[1:]))


@pytest.mark.parametrize("state, lit_ms, switches", [
    (WifiState.NO_MODULE, 10_000, 0),       # steady on
    (WifiState.CONNECTING, 5_000, 99),      # 5 Hz
    (WifiState.UP, 500, 19),                # 50 ms a second
    (WifiState.NOT_PROVISIONED, 1_000, 19), # two 100 ms flashes every 2 s
])
def test_each_link_state_has_its_pattern(status: ctypes.CDLL, state: WifiState, lit_ms: int, switches: int) -> None:
    assert _lit(status, int(state), 0, 10_000) == (lit_ms, switches)


def test_the_pattern_survives_the_millisecond_wrap(status: ctypes.CDLL) -> None:
    assert _lit(status, int(WifiState.NO_MODULE), 0xFFFF_FFFF - 500, 1000) == (1000, 0)


def test_the_usb_line_names_the_state(status: ctypes.CDLL) -> None:
    assert status.rw_link_status_text(int(WifiState.UP)) == b"wifi UP"
    assert status.rw_link_status_text(int(WifiState.CONNECTING)) == b"wifi CONNECTING"
    assert b"does not answer" in status.rw_link_status_text(int(WifiState.NO_MODULE))
    assert status.rw_link_status_text(250) == b"wifi ?"
