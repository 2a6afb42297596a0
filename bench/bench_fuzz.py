"""Long libFuzzer runs of the firmware fuzz targets (the CI runs them for seconds: tests/fuzz/).

For each target (fuzz_frame_decode, fuzz_core, fuzz_cobs_decode; firmware/fuzz/), built with clang,
AddressSanitizer and UBSan into build/fuzz: fuzz from the seed corpus for --minutes each, one target at a
time (one core), and print executions, execs/s, edge coverage and features (libFuzzer's cov/ft: at the
start from the seeds alone, and at the end), the corpus it ended with (units, bytes) and the reproducers
it left (crashes, hangs over --timeout-s, out-of-memory or allocations over --rss-limit-mb). Reproducers
are kept under --work-dir/<target>/ (default build/fuzz-bench/); copy one into firmware/fuzz/crashes/ and
replay it with `build/fuzz/fuzz_<target> <file>`.

    uv run python bench/bench_fuzz.py [--minutes 5] [--targets core frame_decode cobs_decode] [--seed 1]
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO_ROOT / "tests" / "fuzz"))

import libfuzzer_runner as lf  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=5.0, help="fuzzing time per target, minutes")
    parser.add_argument("--targets", nargs="+", choices=lf.TARGETS, default=list(lf.TARGETS))
    parser.add_argument("--seed", type=int, default=1, help="libFuzzer -seed")
    parser.add_argument("--timeout-s", type=int, default=2, help="one input running longer is a hang")
    parser.add_argument("--rss-limit-mb", type=int, default=512, help="memory limit and largest allocation")
    parser.add_argument("--work-dir", type=Path, default=REPO_ROOT / "build" / "fuzz-bench")
    args = parser.parse_args(argv)
    if args.minutes <= 0:
        parser.error(f"--minutes: expected > 0, got {args.minutes}")

    build_dir = lf.build()
    print(f"fuzz targets: {build_dir}  (clang {lf.clang_path()}, -fsanitize=fuzzer,address,undefined)")
    print(f"{'target':<14} {'time_s':>7} {'execs':>10} {'execs/s':>8} {'seed cov/ft':>12} {'cov/ft':>11} "
          f"{'corpus':>16} {'crashes':>7}")
    crashes = 0
    for target in args.targets:
        work_dir = args.work_dir / target
        if work_dir.exists():
            shutil.rmtree(work_dir)
        work_dir.mkdir(parents=True)
        result = lf.run(target, build_dir=build_dir, work_dir=work_dir, max_total_time_s=max(1, round(args.minutes * 60)),
                        timeout_s=args.timeout_s, rss_limit_mb=args.rss_limit_mb, seed=args.seed)
        seed_ft = next((line.split("ft: ")[1].split()[0] for line in result.log.splitlines() if "INITED" in line), "?")
        print(f"{target:<14} {result.elapsed_s:7.0f} {result.executions:10d} {result.execs_per_s:8.0f} "
              f"{result.seed_cov:>5}/{seed_ft:<6} {result.cov:>4}/{result.ft:<6} "
              f"{result.corpus_units:>5} units {result.corpus_bytes / 1024:5.0f} KiB {len(result.artifacts):7d}",
              flush=True)
        if result.artifacts or result.returncode != 0:
            crashes += max(1, len(result.artifacts))
            print(f"  exit {result.returncode}; reproducers: {[str(p) for p in result.artifacts]}")
            print("\n".join("  " + line for line in result.log.splitlines()[-40:]))
    print(f"crashes={crashes}  (reproducers left, or failed runs)")
    return 1 if crashes else 0


if __name__ == "__main__":
    sys.exit(main())
