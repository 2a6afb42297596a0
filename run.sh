#!/usr/bin/env bash
# The two commands of the README.
#   ./run.sh demo   set up, then run the SIL demo (arm, 4 m/s, 6 m/s, spin down, disarm) and write the plot
#   ./run.sh test   set up, then run every test (the same command CI runs)
set -euo pipefail
cd "$(dirname "$0")"
# scripts/setup.sh installs uv here when the machine has none of the pinned version
export PATH="$PWD/.tools/uv/bin:$PATH" UV_PYTHON_DOWNLOADS=never
case "${1:-}" in
  demo)
    bash scripts/setup.sh
    shift
    exec uv run --locked wrangler demo --out out/demo.png "$@"
    ;;
  test)
    bash scripts/setup.sh
    shift
    exec uv run --locked pytest "$@"
    ;;
  *)
    echo "usage: ./run.sh demo|test [extra arguments]" >&2
    exit 2
    ;;
esac
