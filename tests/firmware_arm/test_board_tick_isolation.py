"""Static checks that the board's control tick never reaches a bus (issue 17), on the board sources themselves
(the board build cannot run here; docs/board.md "Tick and background loop").

- The tick (main.cpp's control_tick, run in the TC3 interrupt) calls only the ESC apply, the encoder latch,
  rw_core_tick and the watchdog feed, never a background service.
- The HAL functions the core calls inside the tick (the link and USB serial rw_hal_link functions, the spindle's
  rw_hal_spindle) touch only their queues or the split transaction: no WiFiNINA, Serial, USB or Dynamixel call,
  no delay or clock read.
- The interrupt priorities are ordered as docs/board.md reasons: encoder above the spindle UART above the tick
  above USB.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
ARDUINO = REPO_ROOT / "firmware" / "hal" / "arduino"
BUS_CALLS = re.compile(r"\b(udp\.|WiFi\.|WiFiDrv::|Serial1?\.|SerialUSB\.|USB->|USBDevice\.|dxl\.|delay\w*\(|millis\(|"
                       r"micros\(|digitalRead\(|rw_arduino_\w+_service\()")


def function_body(source: str, name: str) -> str:
    """The body of the first function definition called name (braces matched)."""
    match = re.search(rf"^[\w:<>\*\s]*\b{re.escape(name)}\s*\([^;{{]*\)\s*\{{", source, re.MULTILINE)
    assert match, f"no definition of {name}"
    depth, i = 1, match.end()
    while depth:
        depth += {"{": 1, "}": -1}.get(source[i], 0)
        i += 1
    return source[match.end():i - 1]


def code_only(body: str) -> str:
    return re.sub(r"/\*.*?\*/|//[^\n]*", "", body, flags=re.DOTALL)


def test_the_tick_calls_only_what_runs_in_ram() -> None:
    body = code_only(function_body((REPO_ROOT / "firmware" / "src" / "main.cpp").read_text(), "control_tick"))
    calls = set(re.findall(r"\b(\w+)\s*\(", body)) - {"if", "for", "while", "return"}
    assert calls <= {"rw_arduino_esc_output_apply", "rw_arduino_encoder_latch", "rw_core_tick",
                     "rw_arduino_watchdog_feed", "rope_down"}, calls
    assert "rw_arduino_esc_output_apply" in calls and "rw_core_tick" in calls
    main = (REPO_ROOT / "firmware" / "src" / "main.cpp").read_text()
    assert "rw_arduino_scheduler_begin(control_tick)" in main


def test_the_hal_functions_the_core_calls_in_the_tick_touch_no_bus() -> None:
    tick_side = {
        "arduino_link.cpp": ("link_recv", "link_reply", "link_accept_peer", "link_send"),
        "arduino_serial_link.cpp": ("serial_recv", "serial_send", "serial_accept_peer"),
        "arduino_esc_output.cpp": ("stage_esc",),
    }
    for file, names in tick_side.items():
        source = (ARDUINO / file).read_text()
        for name in names:
            found = BUS_CALLS.findall(code_only(function_body(source, name)))
            assert not found, f"{file}:{name} runs in the tick but calls {found}"
    spindle = code_only(function_body((ARDUINO / "arduino_spindle.cpp").read_text(), "rw_arduino_spindle_hal"))
    assert "rw_spindle_exchange_hal" in spindle, "the spindle's tick side must be the split transaction"


def test_interrupt_priorities_are_ordered_as_documented() -> None:
    header = (ARDUINO / "arduino_scheduler.h").read_text()
    prio = {name: int(value) for name, value in
            re.findall(r"RW_NVIC_PRIORITY_(\w+)\s*=\s*(\d+)u", header)}
    assert prio["ENCODER"] < prio["DXL_UART"] < prio["TICK"] < prio["USB"] <= 3, prio
    source = (ARDUINO / "arduino_scheduler.cpp").read_text()
    for irq, name in (("EIC_IRQn", "ENCODER"), ("SERCOM5_IRQn", "DXL_UART"), ("USB_IRQn", "USB"),
                      ("TC3_IRQn", "TICK")):
        assert f"NVIC_SetPriority({irq}, RW_NVIC_PRIORITY_{name})" in source, f"{irq} not set to {name}"
