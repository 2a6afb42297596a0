"""The C decoder, the COBS decoder and the whole firmware core under libFuzzer (AddressSanitizer + UBSan).

Each target is built with clang (firmware/fuzz/CMakeLists.txt, into build/fuzz) and fuzzed from its seed
corpus (firmware/fuzz/corpus/<target>/) for a few seconds: the run must end by its time limit (exit 0)
with no crash, hang (-timeout), out-of-memory or oversized allocation (-rss_limit_mb/-malloc_limit_mb),
sanitizer report or invariant trap (the targets' headers list their invariants), and must have run
the target for real (executions, and coverage no lower than the seed corpus reaches by itself).
Total fuzzing time here: 30 s; bench/bench_fuzz.py runs the long version.
"""

from __future__ import annotations

import filecmp
import subprocess
import sys
from pathlib import Path

import libfuzzer_runner as lf
import pytest

# seconds of fuzzing per target in CI; the core target is the slowest per input (thousands of ticks)
CI_BUDGET_S = {"frame_decode": 8, "core": 15, "cobs_decode": 5}
# edges the seed corpus alone reaches (measured: frame_decode 245, core 802, cobs_decode 29), with slack:
# a harness change that stops reaching the decoder or the command handling falls under these
MIN_SEED_COV = {"frame_decode": 200, "core": 650, "cobs_decode": 25}
# inputs run at the least (measured on 2 busy cores: frame_decode and cobs_decode ~40,000/s, core ~250/s)
MIN_EXECUTIONS = {"frame_decode": 10_000, "core": 300, "cobs_decode": 10_000}


@pytest.mark.parametrize("target", lf.TARGETS)
def test_bounded_fuzz_run_finds_nothing(target: str, fuzz_build_dir: Path, tmp_path: Path) -> None:
    result = lf.run(target, build_dir=fuzz_build_dir, work_dir=tmp_path, max_total_time_s=CI_BUDGET_S[target])
    tail = "\n".join(result.log.splitlines()[-60:])
    assert result.artifacts == (), f"fuzz_{target} left reproducers {[p.name for p in result.artifacts]}:\n{tail}"
    assert result.returncode == 0, f"fuzz_{target} exited {result.returncode}:\n{tail}"
    assert result.executions >= MIN_EXECUTIONS[target], tail
    assert result.seed_cov >= MIN_SEED_COV[target], f"seed corpus reaches only {result.seed_cov} edges:\n{tail}"
    assert result.cov >= result.seed_cov


@pytest.mark.parametrize("target", lf.TARGETS)
def test_seed_corpus_matches_the_golden_vectors(target: str, tmp_path: Path) -> None:
    """The committed seeds are what make_corpus.py makes from protocol/vectors/vectors.json today."""
    subprocess.run([sys.executable, str(lf.FUZZ_SOURCE_DIR / "make_corpus.py"), "--out", str(tmp_path)],
                   check=True, capture_output=True, text=True)
    fresh, committed = tmp_path / target, lf.CORPUS_DIR / target
    names = sorted(p.name for p in fresh.iterdir())
    assert len(names) >= 20
    assert names == sorted(p.name for p in committed.iterdir()), "run firmware/fuzz/make_corpus.py"
    _, mismatch, errors = filecmp.cmpfiles(fresh, committed, names, shallow=False)
    assert mismatch == [] and errors == [], "run firmware/fuzz/make_corpus.py"



def test_replay_after_a_key_commit_stays_dropped(fuzz_build_dir: Path) -> None:
    """Regression of the fuzzing finding in firmware/fuzz/crashes/README.md: a signed ARM replayed over WiFi
    after the same key was committed again (6 s later, past the duplicate window) is dropped unanswered."""
    crash = lf.FUZZ_SOURCE_DIR / "crashes" / "replay_after_key_commit"
    result = subprocess.run([str(fuzz_build_dir / "fuzz_core"), str(crash)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr[-3000:]


def test_a_fuzz_run_started_from_a_large_process_is_not_out_of_memory_at_once(fuzz_build_dir: Path,
                                                                              tmp_path: Path) -> None:
    """A test worker that has loaded MuJoCo and Numba is 600-700 MB; Linux hands that peak RSS to the program
    it starts, and libFuzzer's -rss_limit_mb reads it: the run was out of memory before its first input (seen
    in a fresh-machine run). The runner counts the limit on top of what the target inherits."""
    script = (
        "import sys; from pathlib import Path; sys.path.insert(0, sys.argv[1]); import libfuzzer_runner as lf\n"
        "ballast = bytearray(700 * 1024 * 1024)\n"
        "ballast[::4096] = b'x' * len(ballast[::4096])  # touched: resident\n"
        "r = lf.run('cobs_decode', build_dir=Path(sys.argv[2]), work_dir=Path(sys.argv[3]), max_total_time_s=2)\n"
        "print(len(r.artifacts), r.returncode)\n")
    out = subprocess.run([sys.executable, "-c", script, str(Path(__file__).parent), str(fuzz_build_dir),
                          str(tmp_path)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.split() == ["0", "0"], out.stdout + out.stderr[-3000:]
