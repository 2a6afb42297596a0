"""Build the libFuzzer targets of firmware/fuzz with clang and run one for a bounded time.

Shared by tests/fuzz/test_fuzz_targets.py (short CI runs) and bench/bench_fuzz.py (long runs). A run
works in its own directory: libFuzzer writes new inputs into work_dir/corpus (the seed corpus in the
repository is only read) and crash/timeout/oom/leak reproducers into work_dir (artifact prefix).
Limits: -timeout (s per input, a hang), -rss_limit_mb and -malloc_limit_mb (MB; one allocation over it
is an "unbounded allocation" and fails the run).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
FUZZ_SOURCE_DIR = REPO_ROOT / "firmware" / "fuzz"
CORPUS_DIR = FUZZ_SOURCE_DIR / "corpus"
DEFAULT_BUILD_DIR = REPO_ROOT / "build" / "fuzz"
TARGETS = ("frame_decode", "core", "cobs_decode")
ARTIFACT_PREFIXES = ("crash-", "leak-", "timeout-", "oom-")

# "#123  DONE   cov: 919 ft: 4687 corp: 670/339Kb ..." (also INITED, NEW, pulse lines)
_STATUS = re.compile(r"^#(\d+)\s+(\w+)\s+cov: (\d+) ft: (\d+) corp: (\d+)/(\d+)(b|Kb|Mb)", re.MULTILINE)
_UNIT = {"b": 1, "Kb": 1024, "Mb": 1024 * 1024}


class ClangMissing(RuntimeError):
    """clang (with its libFuzzer runtime) is not installed."""


def clang_path() -> str | None:
    return shutil.which("clang")


def build(build_dir: Path = DEFAULT_BUILD_DIR) -> Path:
    """Configure (clang) and build every fuzz target into build_dir; returns build_dir."""
    clang = clang_path()
    if clang is None:
        raise ClangMissing("clang not found on PATH (Debian: apt-get install clang libclang-rt-14-dev)")
    if str(Path(__file__).resolve().parents[1]) not in sys.path:  # tests/build_lock.py, also from bench/
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from build_lock import exclusive

    with exclusive(build_dir):
        if not (build_dir / "CMakeCache.txt").exists():
            configure = subprocess.run(["cmake", "-S", str(FUZZ_SOURCE_DIR), "-B", str(build_dir),
                                        f"-DCMAKE_C_COMPILER={clang}"], capture_output=True, text=True)
            if configure.returncode != 0:
                raise RuntimeError(f"fuzz configure failed:\n{configure.stdout}\n{configure.stderr}")
        result = subprocess.run(["cmake", "--build", str(build_dir), "-j2"], capture_output=True, text=True)
    if result.returncode != 0:
        hint = ("\n(the libFuzzer/sanitizer runtime is missing: Debian package libclang-rt-<clang major>-dev)"
                if "libclang_rt" in result.stdout + result.stderr else "")
        raise RuntimeError(f"fuzz build failed:{hint}\n{result.stdout}\n{result.stderr}")
    for target in TARGETS:
        if not (build_dir / f"fuzz_{target}").exists():
            raise RuntimeError(f"fuzz build: {build_dir / f'fuzz_{target}'} missing after the build:\n{result.stdout}")
    return build_dir


@dataclass(frozen=True)
class FuzzRun:
    """What one bounded libFuzzer run did. cov/ft: libFuzzer's edge coverage and features at the end;
    corpus_units/corpus_bytes: the corpus it ended with (seeds + new inputs)."""

    target: str
    returncode: int
    elapsed_s: float
    executions: int
    execs_per_s: float
    seed_cov: int
    cov: int
    ft: int
    corpus_units: int
    corpus_bytes: int
    artifacts: tuple[Path, ...]
    log: str


def inherited_peak_rss_mb() -> int:
    """The peak RSS a process started from this one begins with, in MB: Linux keeps the peak of the image an
    exec replaces in the new program's rusage, and libFuzzer's -rss_limit_mb checks that peak. Started from a
    test worker that has loaded MuJoCo and Numba (600-700 MB), a fuzz target would be out of memory before its
    first input; its own limit is counted on top of this (-malloc_limit_mb, one allocation, is unaffected)."""
    import resource

    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024) + 1


def run(target: str, *, build_dir: Path = DEFAULT_BUILD_DIR, work_dir: Path, max_total_time_s: int,
        timeout_s: int = 2, rss_limit_mb: int = 512, seed: int = 1) -> FuzzRun:
    """Fuzz one target (TARGETS) from its seed corpus for max_total_time_s seconds."""
    if target not in TARGETS:
        raise ValueError(f"target: expected one of {TARGETS}, got {target!r}")
    if not isinstance(max_total_time_s, int) or max_total_time_s < 1:
        raise ValueError(f"max_total_time_s: expected an integer >= 1, got {max_total_time_s!r}")
    new_corpus = work_dir / "corpus"
    new_corpus.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("UBSAN_OPTIONS", "print_stacktrace=1")
    symbolizer = shutil.which("llvm-symbolizer")
    if symbolizer:
        env.setdefault("ASAN_SYMBOLIZER_PATH", symbolizer)
    command = [str(build_dir / f"fuzz_{target}"), f"-max_total_time={max_total_time_s}", f"-timeout={timeout_s}",
               f"-rss_limit_mb={rss_limit_mb + inherited_peak_rss_mb()}", f"-malloc_limit_mb={rss_limit_mb}",
               f"-seed={seed}",
               "-print_final_stats=1", f"-artifact_prefix={work_dir}/", str(new_corpus), str(CORPUS_DIR / target)]
    started = time.monotonic()
    result = subprocess.run(command, cwd=work_dir, capture_output=True, text=True, env=env,
                            timeout=max_total_time_s + 10 * timeout_s + 60)
    elapsed_s = time.monotonic() - started
    log = result.stdout + result.stderr
    status = _STATUS.findall(log)
    seed_cov = next((int(s[2]) for s in status if s[1] == "INITED"), 0)
    last = status[-1] if status else ("0", "", "0", "0", "0", "0", "b")
    executions = int(_stat(log, "number_of_executed_units") or last[0])
    artifacts = tuple(sorted(p for p in work_dir.iterdir() if p.name.startswith(ARTIFACT_PREFIXES)))
    return FuzzRun(target=target, returncode=result.returncode, elapsed_s=elapsed_s, executions=executions,
                   execs_per_s=float(_stat(log, "average_exec_per_sec") or 0.0), seed_cov=seed_cov,
                   cov=int(last[2]), ft=int(last[3]), corpus_units=int(last[4]),
                   corpus_bytes=int(last[5]) * _UNIT[last[6]], artifacts=artifacts, log=log)


def _stat(log: str, name: str) -> str | None:
    match = re.search(rf"^stat::{name}:\s+(\S+)", log, re.MULTILINE)
    return match.group(1) if match else None
