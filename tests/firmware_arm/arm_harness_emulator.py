"""Run the ARM build of the firmware core (firmware/cmake/arm_tick_harness.c) in the unicorn emulator.

The ELF is loaded as the reset handler would leave it (.data at its RAM address, .bss zero), functions are
called by name with the AAPCS (arguments in r0..r3, result in r0), and the harness's fake HAL is driven
through its globals (harness_rx, harness_tx, harness_wheel_rpm, ...), found in the ELF symbol table.

Instruction and cycle counting (count=True) hooks every instruction; the Cortex-M0+ cycle model is the
one in ARM's Cortex-M0+ Technical Reference Manual (instruction timings, zero flash wait states, the
single-cycle multiplier the SAMD21 has): data processing 1, load/store 2, LDM/STM/PUSH 1+N, POP 1+N
(3+N with PC), taken branch 2 (B/BX) or 3 (BL), untaken conditional branch 1. The SAMD21 at 48 MHz runs
its flash with one wait state; sequential fetches are partly hidden, so the real figure lies between this
count and about 1.5x it.

The harness's fake flash holds the test key (TEST_KEY, bytes 0..15), so the emulated core enforces the
signed link: every frame but HELLO must be signed for its session (session_id()) with a growing counter;
SignedHost builds such frames.

Used by tests/firmware_arm/test_arm_build.py and bench/bench_tick_instructions.py.
"""

from __future__ import annotations

import bisect
import os
import shutil
import subprocess
import sys
import struct
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
ARM_BUILD_DIR = Path(os.environ.get("ROBOWRANGLER_ARM_BUILD_DIR", REPO_ROOT / "build" / "arm"))
TOOLCHAIN_FILE = REPO_ROOT / "firmware" / "cmake" / "arm-none-eabi.cmake"
HARNESS_ELF_NAME = "rw_arm_tick_harness.elf"

FLASH_BASE = 0x0000_0000
FLASH_SIZE = 0x0004_0000
RAM_BASE = 0x2000_0000
RAM_SIZE = 0x0000_8000
STACK_TOP = RAM_BASE + RAM_SIZE
# Functions "return" here: an address inside the mapped flash that no code occupies.
RETURN_ADDRESS = FLASH_BASE + FLASH_SIZE - 0x10
HARNESS_TX_REPLY = 1
HARNESS_TX_SEND = 2
TEST_KEY = bytes(range(16))  # harness_test_key in arm_tick_harness.c: the provisioned key, never a real one


class ArmToolchainMissing(RuntimeError):
    """arm-none-eabi-gcc is not installed (Debian: gcc-arm-none-eabi libnewlib-arm-none-eabi)."""


class ArmBuildError(RuntimeError):
    """The cross build of the core failed; the message holds CMake's output."""


def toolchain_available() -> bool:
    """True when arm-none-eabi-gcc and arm-none-eabi-size are on PATH."""
    return shutil.which("arm-none-eabi-gcc") is not None and shutil.which("arm-none-eabi-size") is not None


def build_arm(*, build_dir: Path = ARM_BUILD_DIR) -> Path:
    """Configure (once) and build the ARM harness ELF with CMake; returns the ELF path.

    Raises ArmToolchainMissing without the toolchain and ArmBuildError when CMake fails.
    """
    if not toolchain_available():
        raise ArmToolchainMissing("arm-none-eabi-gcc not found: apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi")
    if str(Path(__file__).resolve().parents[1]) not in sys.path:  # tests/build_lock.py, also from bench/
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from build_lock import exclusive

    with exclusive(build_dir):
        if not (build_dir / "CMakeCache.txt").exists():
            cfg = subprocess.run(["cmake", "-S", str(REPO_ROOT / "firmware"), "-B", str(build_dir),
                                  f"-DCMAKE_TOOLCHAIN_FILE={TOOLCHAIN_FILE}"], capture_output=True, text=True)
            if cfg.returncode != 0:
                raise ArmBuildError(f"ARM configure failed:\n{cfg.stdout}\n{cfg.stderr}")
        result = subprocess.run(["cmake", "--build", str(build_dir), "-j2"], capture_output=True, text=True)
    if result.returncode != 0:
        raise ArmBuildError(f"ARM build failed:\n{result.stdout}\n{result.stderr}")
    return build_dir / HARNESS_ELF_NAME


NOLOAD_RAM_SECTIONS = (".bss", ".stack", ".heap")
RAM_SECTIONS = (".data", ".relocate")


def section_sizes(elf_path: Path) -> dict[str, int]:
    """Allocated sections of an ELF: name -> size in bytes."""
    from elftools.elf.constants import SH_FLAGS
    from elftools.elf.elffile import ELFFile

    out: dict[str, int] = {}
    with open(elf_path, "rb") as fh:
        for sec in ELFFile(fh).iter_sections():
            if sec["sh_flags"] & SH_FLAGS.SHF_ALLOC and sec["sh_size"]:
                out[sec.name] = sec["sh_size"]
    return out


def flash_ram(sizes: dict[str, int]) -> tuple[int, int]:
    """(flash bytes, static RAM bytes) of a section table: flash = code + rodata + .data's initial values,
    RAM = .data + .bss (the stack comes on top)."""
    flash = sum(n for name, n in sizes.items() if name not in NOLOAD_RAM_SECTIONS)
    ram = sum(n for name, n in sizes.items() if name in RAM_SECTIONS or name in NOLOAD_RAM_SECTIONS)
    return flash, ram


@dataclass(frozen=True)
class Symbol:
    name: str
    address: int
    size: int
    kind: str  # "FUNC" or "OBJECT"


def read_symbols(elf_path: Path) -> dict[str, Symbol]:
    """Function and object symbols of an ELF by name (Thumb bit cleared from function addresses)."""
    from elftools.elf.elffile import ELFFile

    out: dict[str, Symbol] = {}
    with open(elf_path, "rb") as fh:
        elf = ELFFile(fh)
        symtab = elf.get_section_by_name(".symtab")
        for sym in symtab.iter_symbols():
            kind = sym["st_info"]["type"]
            if kind not in ("STT_FUNC", "STT_OBJECT") or not sym.name:
                continue
            addr = sym["st_value"] & ~1 if kind == "STT_FUNC" else sym["st_value"]
            out[sym.name] = Symbol(sym.name, addr, sym["st_size"], kind[4:])
    return out


@dataclass
class CallProfile:
    """What one emulated call executed.

    instructions: instructions retired; cycles: Cortex-M0+ cycles by the model in the module docstring;
    per_function: instructions per function name; per_class: instructions per class
    ("alu", "load_store", "multiple", "branch", "call"); runtime_by_caller: instructions spent in runtime
    library routines (libgcc soft-float and division, memcpy/memset, libm) per nearest calling function of
    ours, found with a shadow call stack; stack_bytes: deepest stack use below the caller's stack pointer;
    inclusive / inclusive_cycles: instructions / modelled cycles spent inside each function named in the
    call's inclusive_roots, callees included (e.g. the whole of rw_frame_tag_valid with its SipHash).
    """

    instructions: int = 0
    cycles: int = 0
    per_function: Counter = field(default_factory=Counter)
    per_class: Counter = field(default_factory=Counter)
    runtime_by_caller: Counter = field(default_factory=Counter)
    stack_bytes: int = 0
    inclusive: Counter = field(default_factory=Counter)
    inclusive_cycles: Counter = field(default_factory=Counter)


def is_runtime_routine(name: str) -> bool:
    """True for libgcc/newlib/libm routines (soft-float, division, memcpy/memset, floorf/ceilf)."""
    return name.startswith("__") or name in ("memcpy", "memset", "memmove", "floorf", "ceilf", "sqrtf", "fabsf")


def _thumb_class(hw: int, next_hw: int) -> tuple[str, int, int]:
    """(class, size in bytes, base cycles) of the Thumb instruction whose first halfword is hw.

    Branch penalties are added by the caller once it knows whether the branch was taken.
    """
    if (hw >> 11) in (0b11101, 0b11110, 0b11111):  # 32-bit encodings: BL (and MSR/MRS/DMB, not used here)
        return ("call", 4, 3) if (hw >> 11) == 0b11110 and (next_hw >> 14) == 0b11 else ("alu", 4, 1)
    top4, top5 = hw >> 12, hw >> 11
    if top5 == 0b01001 or top4 in (0b0101, 0b0110, 0b0111, 0b1000, 0b1001):
        return "load_store", 2, 2
    if top4 == 0b1100:  # LDM/STM
        return "multiple", 2, 1 + bin(hw & 0xFF).count("1")
    if (hw >> 9) & 0b1111011 == 0b1011010:  # PUSH/POP: 1011 x10x
        n = bin(hw & 0x1FF).count("1")
        pops_pc = (hw >> 11) & 1 and (hw >> 8) & 1
        return ("branch", 2, 3 + n - 1) if pops_pc else ("multiple", 2, 1 + n)
    if top4 == 0b1101 and ((hw >> 8) & 0xF) not in (0xE, 0xF):  # B<cond>
        return "branch", 2, 1
    if top5 == 0b11100:  # B
        return "branch", 2, 2
    if (hw >> 7) == 0b010001110:  # BX
        return "branch", 2, 2
    if (hw >> 7) == 0b010001111:  # BLX
        return "call", 2, 2
    return "alu", 2, 1


class HarnessEmulator:
    """The ARM harness ELF in a unicorn Cortex-M0 CPU.

    Construct with the ELF path; call reset() (harness_init) before a scenario. Not thread-safe.
    """

    def __init__(self, elf_path: Path) -> None:
        from elftools.elf.elffile import ELFFile
        from unicorn import UC_ARCH_ARM, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
        from unicorn.arm_const import UC_CPU_ARM_CORTEX_M0

        self.elf_path = Path(elf_path)
        self.symbols = read_symbols(self.elf_path)
        funcs = sorted((s.address, s.size, s.name) for s in self.symbols.values() if s.kind == "FUNC")
        self._func_starts = [f[0] for f in funcs]
        self._funcs = funcs
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M0)
        self.uc.mem_map(FLASH_BASE, FLASH_SIZE)
        self.uc.mem_map(RAM_BASE, RAM_SIZE)
        with open(self.elf_path, "rb") as fh:
            elf = ELFFile(fh)
            for seg in elf.iter_segments():
                if seg["p_type"] == "PT_LOAD" and seg["p_filesz"] > 0:
                    self.uc.mem_write(seg["p_vaddr"], seg.data())
        self.uc.mem_write(RETURN_ADDRESS, b"\x00\xbf" * 4)  # NOPs, never executed
        self._profile: CallProfile | None = None
        # (address, size, base cycles, inclusive roots active) of a conditional branch awaiting its outcome
        self._pending: tuple[int, int, int, tuple[str, ...]] | None = None
        self._roots: tuple[str, ...] = ()
        self._stack: list[str] = []
        from unicorn.arm_const import UC_ARM_REG_SP

        self._sp_reg = UC_ARM_REG_SP

    # ---- calls -----------------------------------------------------------------------------------
    def call(self, name: str, *args: int, count: bool = False, max_instructions: int = 5_000_000,
             inclusive_roots: tuple[str, ...] = ()) -> tuple[int, CallProfile | None]:
        """Call the function `name` with up to four integer arguments; returns (r0, profile or None).

        With count=True, the profile's inclusive counters cover the functions named in inclusive_roots.
        """
        from unicorn import UC_HOOK_CODE
        from unicorn.arm_const import UC_ARM_REG_LR, UC_ARM_REG_PC, UC_ARM_REG_R0, UC_ARM_REG_SP

        if name not in self.symbols or self.symbols[name].kind != "FUNC":
            raise KeyError(f"name: expected a function in {self.elf_path.name}, got {name!r}")
        if len(args) > 4:
            raise ValueError(f"args: expected at most 4 register arguments, got {len(args)}")
        for i, value in enumerate(args):
            self.uc.reg_write(UC_ARM_REG_R0 + i, value & 0xFFFF_FFFF)
        self.uc.reg_write(UC_ARM_REG_SP, STACK_TOP)
        self.uc.reg_write(UC_ARM_REG_LR, RETURN_ADDRESS | 1)
        hook = None
        self._profile = CallProfile() if count else None
        self._pending = None
        self._stack = []
        self._roots = tuple(inclusive_roots)
        if count:
            hook = self.uc.hook_add(UC_HOOK_CODE, self._on_instruction)
            self.uc.ctl_flush_tb()  # blocks translated before the hook existed would run unhooked
        try:
            self.uc.emu_start(self.symbols[name].address | 1, RETURN_ADDRESS, count=max_instructions)
        finally:
            if hook is not None:
                self.uc.hook_del(hook)
                self.uc.ctl_flush_tb()
        if self.uc.reg_read(UC_ARM_REG_PC) & ~1 != RETURN_ADDRESS:
            raise RuntimeError(f"{name} did not return within {max_instructions} instructions")
        if self._pending is not None and self._profile is not None:
            self._settle_branch(RETURN_ADDRESS)
        return self.uc.reg_read(UC_ARM_REG_R0), self._profile

    def _settle_branch(self, next_address: int) -> None:
        address, size, base, active = self._pending
        taken = next_address != address + size
        hw = struct.unpack("<H", self.uc.mem_read(address, 2))[0]
        is_conditional = (hw >> 12) == 0b1101
        cycles = base + (1 if (taken and is_conditional) else 0)
        self._profile.cycles += cycles
        for root in active:
            self._profile.inclusive_cycles[root] += cycles
        self._pending = None

    def _on_instruction(self, uc, address: int, size: int, _user) -> None:  # noqa: ANN001
        prof = self._profile
        depth = STACK_TOP - uc.reg_read(self._sp_reg)
        if depth > prof.stack_bytes:
            prof.stack_bytes = depth
        if self._pending is not None:
            self._settle_branch(address)
        raw = bytes(uc.mem_read(address, 4))
        hw, next_hw = struct.unpack("<HH", raw)
        cls, _, cycles = _thumb_class(hw, next_hw)
        prof.instructions += 1
        prof.per_class[cls] += 1
        i = bisect.bisect_right(self._func_starts, address) - 1
        func = self._funcs[i][2] if i >= 0 and address < self._funcs[i][0] + max(self._funcs[i][1], 2) else f"?0x{address:x}"
        prof.per_function[func] += 1
        stack = self._stack
        if not stack or stack[-1] != func:
            if func in stack:
                del stack[stack.index(func) + 1:]
            else:
                stack.append(func)
        if is_runtime_routine(func):
            caller = next((f for f in reversed(stack) if not is_runtime_routine(f)), "?")
            prof.runtime_by_caller[caller] += 1
        active = tuple(root for root in self._roots if root in stack) if self._roots else ()
        for root in active:
            prof.inclusive[root] += 1
        if cls == "branch" and (hw >> 12) == 0b1101:
            self._pending = (address, size, cycles, active)
        else:
            prof.cycles += cycles
            for root in active:
                prof.inclusive_cycles[root] += cycles

    # ---- memory helpers --------------------------------------------------------------------------
    def read_u32(self, name: str) -> int:
        return struct.unpack("<I", self.uc.mem_read(self.symbols[name].address, 4))[0]

    def write_u32(self, name: str, value: int) -> None:
        self.uc.mem_write(self.symbols[name].address, struct.pack("<I", value & 0xFFFF_FFFF))

    def write_u16(self, name: str, value: int) -> None:
        self.uc.mem_write(self.symbols[name].address, struct.pack("<H", value & 0xFFFF))

    # ---- the fake HAL ----------------------------------------------------------------------------
    def reset(self) -> None:
        """harness_init: the core to its boot state, wheel stopped, battery 14.8 V, link idle."""
        self.call("harness_init")

    def set_wheel_rpm(self, rpm: int) -> None:
        self.write_u32("harness_wheel_rpm", rpm)

    def set_battery_mv(self, mv: int) -> None:
        self.write_u16("harness_battery_mv", mv)

    def put_datagram(self, frame: bytes) -> None:
        """The next recv() of the core returns this datagram."""
        cap = self.symbols["harness_rx"].size
        if len(frame) > cap:
            raise ValueError(f"frame: expected at most {cap} bytes, got {len(frame)}")
        self.uc.mem_write(self.symbols["harness_rx"].address, bytes(frame))
        self.write_u32("harness_rx_len", len(frame))

    def tx_count(self) -> int:
        return self.read_u32("harness_tx_count")

    def last_tx(self) -> tuple[int, bytes]:
        """(HARNESS_TX_REPLY or HARNESS_TX_SEND, bytes) of the last datagram the core sent."""
        n = self.read_u32("harness_tx_len")
        return self.read_u32("harness_tx_kind"), bytes(self.uc.mem_read(self.symbols["harness_tx"].address, n))

    def pulse_us(self) -> int:
        return self.read_u32("harness_pulse_us")

    def state(self) -> int:
        return self.call("harness_state")[0] & 0xFF

    def session_id(self) -> int:
        """The session id of the core's current boot (its stored boot counter; 1 after the first tick)."""
        return self.call("harness_session_id")[0]

    def siphash(self, data: bytes, *, count: bool = False, offset: int = 0) -> tuple[int, CallProfile | None]:
        """rw_siphash24(harness_test_key, data) run on the emulated core: (64-bit tag, profile or None).

        data is staged in harness_rx at byte offset `offset` (0..3: 0 is word aligned, the others exercise the
        unaligned path); at most its size; use between ticks only.
        """
        from unicorn.arm_const import UC_ARM_REG_R1

        cap = self.symbols["harness_rx"].size
        if not 0 <= offset <= 3:
            raise ValueError(f"offset: expected 0..3, got {offset}")
        if len(data) + offset > cap:
            raise ValueError(f"data: expected at most {cap - offset} bytes, got {len(data)}")
        rx = self.symbols["harness_rx"].address + offset
        self.uc.mem_write(rx, bytes(data))
        low, profile = self.call("rw_siphash24", self.symbols["harness_test_key"].address, rx, len(data), count=count)
        return low | (self.uc.reg_read(UC_ARM_REG_R1) << 32), profile

    def tick(self, now_us: int, *, count: bool = False,
             inclusive_roots: tuple[str, ...] = ()) -> tuple[list[tuple[int, bytes]], CallProfile | None]:
        """One control tick at now_us; returns the datagrams sent in it and the profile (count=True).

        With count=True only rw_core_tick itself (and what it calls) is profiled, not the harness's clock;
        inclusive_roots as in call().
        """
        before = self.tx_count()
        if count:
            self.call("harness_set_clock", now_us)
            _, profile = self.call("rw_core_tick", self.symbols["harness_core"].address,
                                   self.symbols["harness_hal"].address, now_us, count=True,
                                   inclusive_roots=inclusive_roots)
        else:
            _, profile = self.call("harness_tick", now_us)
        sent = [self.last_tx()] if self.tx_count() != before else []
        return sent, profile


class SignedHost:
    """The host side of the signed link to the emulated core: frames signed with TEST_KEY for the core's
    session, sequence numbers and counters growing by one per frame (the first frame gets seq 1, counter 1).

    session_id: the core's session (emu.session_id() once it has ticked; the harness's first boot is 1).
    """

    def __init__(self, *, session_id: int = 1, key: bytes = TEST_KEY) -> None:
        self.session_id = session_id
        self.key = key
        self.seq = 0
        self.counter = 0

    def frame(self, message, *, seq: int | None = None) -> bytes:  # noqa: ANN001
        """message signed afresh (next counter); seq: the next sequence number unless given (a retransmission
        keeps its seq)."""
        from robowrangler.protocol import generated as proto

        if seq is None:
            self.seq = (self.seq + 1) & 0xFFFF
            seq = self.seq
        self.counter += 1
        return proto.encode_frame(message, seq, key=self.key, session_id=self.session_id, counter=self.counter)

    def unsigned(self, message) -> bytes:  # noqa: ANN001
        """message framed without a signature (dropped over WiFi by the core)."""
        from robowrangler.protocol import generated as proto

        self.seq = (self.seq + 1) & 0xFFFF
        return proto.encode_frame(message, self.seq)
