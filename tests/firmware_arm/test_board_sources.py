"""Static checks of the board-side sources and of platformio.ini (PlatformIO itself cannot run here).

- Arduino headers appear only in firmware/hal/arduino/ and firmware/src/ (the core and the SIL stay portable).
- platformio.ini points at directories that exist, selects the core, the arduino HAL and main.cpp for the
  board and the core alone for the native Unity tests, and pins every library and the platform to an
  exact version.
"""

from __future__ import annotations

import configparser
import re
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
FIRMWARE = REPO_ROOT / "firmware"
ARDUINO_ONLY_HEADERS = re.compile(r'#\s*include\s*[<"](Arduino|WiFiNINA|WiFiUdp|FlashStorage|Adafruit_SleepyDog|'
                                  r'Dynamixel2Arduino|wiring_private|SPI)\.h[>"]')


def _platformio() -> configparser.ConfigParser:
    cfg = configparser.ConfigParser(interpolation=None, inline_comment_prefixes=(";",))
    cfg.read(REPO_ROOT / "platformio.ini")
    return cfg


def _lines(value: str) -> list[str]:
    return [line.strip() for line in value.strip().splitlines() if line.strip()]


def test_arduino_headers_only_in_the_board_code() -> None:
    offenders = []
    for path in FIRMWARE.rglob("*"):
        if path.suffix not in (".c", ".h", ".cpp", ".hpp"):
            continue
        rel = path.relative_to(FIRMWARE)
        if rel.parts[:2] == ("hal", "arduino") or rel.parts[0] == "src":
            continue
        if ARDUINO_ONLY_HEADERS.search(path.read_text(errors="replace")):
            offenders.append(str(rel))
    assert not offenders, f"Arduino headers outside firmware/hal/arduino and firmware/src: {offenders}"


def test_board_code_is_complete() -> None:
    hal = FIRMWARE / "hal" / "arduino"
    for interface in ("esc_output", "encoder", "battery", "link", "scheduler"):
        assert (hal / f"arduino_{interface}.cpp").is_file(), f"no board implementation of rw_hal_{interface}.h"
    main = (FIRMWARE / "src" / "main.cpp").read_text()
    assert "void setup()" in main and "void loop()" in main
    assert "rw_core_tick(" in main and "rw_core_init(" in main


def test_platformio_directories_exist() -> None:
    cfg = _platformio()
    pio = cfg["platformio"]
    assert (REPO_ROOT / pio["src_dir"]).resolve() == FIRMWARE
    assert (REPO_ROOT / pio["test_dir"]).is_dir(), "test_dir must be the Unity suite's folder"
    for section in ("env", "env:mkrwifi1010", "env:native"):
        for flag in _lines(cfg[section].get("build_flags", "")):
            if flag.startswith("-I"):
                inc = flag[2:].strip()
                assert (REPO_ROOT / inc).is_dir(), f"[{section}] include directory {inc} does not exist"


def test_platformio_source_selection() -> None:
    cfg = _platformio()
    board = " ".join(_lines(cfg["env:mkrwifi1010"]["build_src_filter"]))
    native = " ".join(_lines(cfg["env:native"]["build_src_filter"]))
    assert board.startswith("-<*>") and native.startswith("-<*>"), "filters must start from nothing"
    for needed in ("+<core/>", "+<hal/arduino/>", "+<src/>"):
        assert needed in board
        assert (FIRMWARE / needed[2:-2]).is_dir()
    assert "hal/sil" not in board and "cmake" not in board
    assert _lines(cfg["env:native"]["build_src_filter"]) == ["-<*>", "+<core/>"], "native tests link the core only"
    assert cfg["env:native"]["test_framework"] == "unity"
    assert "-lm" in _lines(cfg["env:native"]["build_flags"])


def test_platformio_versions_are_pinned() -> None:
    cfg = _platformio()
    board = cfg["env:mkrwifi1010"]
    assert re.fullmatch(r"atmelsam@\d+\.\d+\.\d+", board["platform"]), board["platform"]
    deps = _lines(board["lib_deps"])
    names = [d.split("@")[0].strip() for d in deps]
    for needed in ("arduino-libraries/WiFiNINA", "robotis-git/Dynamixel2Arduino", "cmaglie/FlashStorage"):
        assert needed in names, f"{needed} missing from lib_deps"
    for dep in deps:
        assert re.search(r"@\s*\d+\.\d+\.\d+$", dep), f"lib_deps entry not pinned to an exact version: {dep}"
    assert "-Werror" in _lines(board["build_src_flags"]), "warnings as errors for our sources"
