"""Install size of each distribution: a fresh virtual environment per distribution (uv, this Python), the
size of its site-packages and the number of distributions in it.

    uv run python bench/bench_install_size.py

Measures: `uv pip install ./host` (robowrangler: what a board user installs) and `uv pip install ./sim`
(robowrangler-sim, which pulls the host in), each into an empty venv; sizes are of site-packages on disk
(files as installed, MiB = 2**20 bytes), the venv's own pip/setuptools excluded (uv venvs have none).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]


def _size_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file() and not f.is_symlink())


def measure(member: str) -> tuple[int, int]:
    uv = shutil.which("uv") or sys.exit("uv is not on PATH (scripts/setup.sh installs it)")
    env = {**os.environ, "UV_PYTHON_DOWNLOADS": "never"}
    env.pop("VIRTUAL_ENV", None)
    with tempfile.TemporaryDirectory() as tmp:
        venv = Path(tmp) / "venv"
        subprocess.run([uv, "venv", "--quiet", "--python", sys.executable, str(venv)], check=True, env=env)
        subprocess.run([uv, "pip", "install", "--quiet", "--python", str(venv / "bin" / "python"),
                        str(REPO_ROOT / member)], check=True, env=env)
        site = next((venv / "lib").glob("python*/site-packages"))
        dists = len(list(site.glob("*.dist-info")))
        return _size_bytes(site), dists


def main() -> None:
    print(f"{'distribution':<20} {'site-packages':>14} {'distributions':>14}")
    for name, member in (("robowrangler", "host"), ("robowrangler-sim", "sim")):
        size, dists = measure(member)
        print(f"{name:<20} {size / 2**20:>10.1f} MiB {dists:>14}", flush=True)


if __name__ == "__main__":
    main()
