"""Flash and RAM of the firmware core built for the board's Cortex-M0+, and of the whole board firmware.

Core: builds the ARM harness ELF (firmware/cmake/arm-none-eabi.cmake; core + fake HAL + libgcc/newlib-nano
routines it pulls in) and sums its sections with pyelftools: flash = .text + .ARM.exidx + .data (the
initial values live in flash), RAM = .data + .bss (the stack comes on top). Also prints the core's share
per owner from the symbol table (by name: the link's SipHash-2-4 and the configuration record are shown
apart), the size of struct rw_core, and the size of every object of the core library before the linker
drops unused sections (rw_cobs.c, the USB serial framing, is used by the board's serial HAL, not by the core,
so it is not in the harness ELF).

Board: if an ELF of the whole board firmware is given (--board-elf, e.g. .pio/build/mkrwifi1010/firmware.elf
after `pio run -e mkrwifi1010`), prints the same figures for it.

    uv run python bench/bench_firmware_size.py [--board-elf PATH]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections import Counter
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT / "tests" / "firmware_arm"))

import arm_harness_emulator as ah  # noqa: E402

section_sizes = ah.section_sizes
flash_ram = ah.flash_ram


def owner_of(name: str) -> str:
    if name == "harness_core":
        return "core state (struct rw_core)"
    if name in ("rw_siphash24", "sip_round", "rw_frame_sign", "rw_frame_tag_valid"):
        return "link MAC (SipHash-2-4, sign/verify)"
    if name.startswith(("rw_config_", "rw_crc32")):
        return "config record (rw_config, CRC-32)"
    if name.startswith("rw_cobs_"):
        return "COBS (serial framing)"
    if name.startswith(("rw_msg_", "rw_frame_", "rw_crc16", "rw_param_table", "msg_infos")):
        return "protocol codec (generated)"
    if name.startswith("rw_") or name in ("supervise", "control", "queue_telemetry", "send_verdict", "execute",
                                           "sat_u16", "refuse", "cmd_arm", "cmd_disarm", "queue_param_value"):
        return "core"
    if name.startswith(("harness_", "fake_", "Reset_Handler", "Fault_Handler", "main")):
        return "harness (not on the board)"
    if name.startswith("__") or name in ("memcpy", "memset", "floorf", "ceilf"):
        return "libgcc / newlib-nano"
    return "core (static helpers)"


def report(title: str, elf_path: Path) -> None:
    sizes = section_sizes(elf_path)
    flash, ram = flash_ram(sizes)
    print(f"{title}: {elf_path}")
    print(f"  flash (text+rodata+data): {flash:>7} B   ({flash / 1024:.1f} KB of 248 KB after the bootloader)")
    print(f"  RAM   (data+bss):         {ram:>7} B   ({ram / 1024:.1f} KB of 32 KB, stack not included)")
    print("  sections:", ", ".join(f"{k} {v}" for k, v in sizes.items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--board-elf", type=Path, default=None, help="ELF of the whole board firmware")
    args = parser.parse_args()

    elf = ah.build_arm()
    report("core for cortex-m0plus (-Os, harness ELF)", elf)
    symbols = ah.read_symbols(elf)
    by_owner_flash: Counter = Counter()
    by_owner_ram: Counter = Counter()
    for sym in symbols.values():
        target = by_owner_ram if ah.RAM_BASE <= sym.address < ah.RAM_BASE + ah.RAM_SIZE else by_owner_flash
        target[owner_of(sym.name)] += sym.size
    print("  flash by owner (symbol sizes):")
    for owner, n in by_owner_flash.most_common():
        print(f"    {owner:<38}{n:>7} B")
    print("  RAM by owner (symbol sizes):")
    for owner, n in by_owner_ram.most_common():
        print(f"    {owner:<38}{n:>7} B")
    print(f"  sizeof(rw_core) = {symbols['harness_core'].size} B")
    archive = elf.parent / "librw_core.a"
    listing = subprocess.run(["arm-none-eabi-size", str(archive)], capture_output=True, text=True)
    if listing.returncode == 0:
        print(f"  core library objects before --gc-sections ({archive.name}; text includes rodata):")
        print(f"    {'object':<34}{'text':>7}{'data':>6}{'bss':>6}")
        for line in listing.stdout.splitlines()[1:]:
            cols = line.split()
            if len(cols) >= 6:
                print(f"    {cols[5].split('(')[0]:<34}{cols[0]:>7}{cols[1]:>6}{cols[2]:>6}")
    else:
        print(f"  core library objects: arm-none-eabi-size failed: {listing.stderr.strip()}")

    board = args.board_elf
    if board is None:
        default = REPO_ROOT / ".pio" / "build" / "mkrwifi1010" / "firmware.elf"
        board = default if default.exists() else None
    if board is not None:
        report("whole board firmware", board)
    else:
        print("whole board firmware: no ELF (run `pio run -e mkrwifi1010`, or pass --board-elf)")


if __name__ == "__main__":
    main()
