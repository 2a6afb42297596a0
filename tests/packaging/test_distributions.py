"""Two distributions, one repository: the host (`robowrangler`) installs and runs without the simulator, and
names the package to add when a simulator verb is asked for; the simulator (`robowrangler-sim`) adds its verbs
to `wrangler` through the entry point group."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from robowrangler.cli.main import main
from robowrangler.cli.plugins import ENTRY_POINT_GROUP, SIMULATOR_VERBS, LoadedPlugins, load_plugins

REPO_ROOT = Path(__file__).resolve().parents[2]
HOST_PACKAGE = REPO_ROOT / "host" / "robowrangler"
# What a board user must not be made to install (the simulator's dependencies).
SIMULATOR_ONLY = {"robowrangler_sim", "mujoco", "cv2", "numba", "scipy"}


def _imported_roots(path: Path) -> set[str]:
    roots: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            roots.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
    return roots


def test_host_source_never_imports_the_simulator_or_its_dependencies():
    offenders = {str(p.relative_to(REPO_ROOT)): sorted(_imported_roots(p) & SIMULATOR_ONLY)
                 for p in HOST_PACKAGE.rglob("*.py")}
    assert {k: v for k, v in offenders.items() if v} == {}


def test_the_simulator_registers_its_verbs_through_the_entry_point():
    loaded = load_plugins(ENTRY_POINT_GROUP)
    assert loaded.problems == ()
    names = {command.name for command in loaded.commands}
    assert {"sil", "demo", "identify"} <= names
    assert names <= set(SIMULATOR_VERBS), "a plugin verb the host's stand-in list does not know"


def test_a_group_nobody_registers_loads_nothing_and_reports_nothing():
    assert load_plugins("robowrangler.no_such_group") == LoadedPlugins((), ())


def test_sil_help_comes_from_the_plugin(capsys):
    assert main(["sil", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--scenario" in out and "needs robowrangler-sim" not in out


@pytest.fixture(scope="module")
def host_only_venv(tmp_path_factory, skip_unless_ci) -> Path:
    """A fresh virtual environment with only ./host installed (what `pip install robowrangler` gives)."""
    uv = shutil.which("uv")
    if uv is None:
        skip_unless_ci("uv not on PATH")
    venv = tmp_path_factory.mktemp("host_only") / "venv"
    env = {**os.environ, "UV_PYTHON_DOWNLOADS": "never"}
    env.pop("VIRTUAL_ENV", None)
    subprocess.run([uv, "venv", "--quiet", "--python", sys.executable, str(venv)], check=True, env=env)
    subprocess.run([uv, "pip", "install", "--quiet", "--python", str(venv / "bin" / "python"),
                    str(REPO_ROOT / "host")], check=True, env=env, timeout=600)
    return venv


def test_host_only_install_has_no_simulator_and_names_it(host_only_venv):
    py = host_only_venv / "bin" / "python"
    probe = subprocess.run([str(py), "-c", "import importlib.util as u; print([m for m in "
                            "('robowrangler_sim','mujoco','cv2','numba','scipy','matplotlib') if u.find_spec(m)])"],
                           capture_output=True, text=True, check=True)
    assert probe.stdout.strip() == "[]"
    wrangler = host_only_venv / "bin" / "wrangler"
    listing = subprocess.run([str(wrangler), "--help"], capture_output=True, text=True, timeout=120)
    assert listing.returncode == 0 and "keygen" in listing.stdout and "needs robowrangler-sim" in listing.stdout
    for verb in ("sil", "demo"):
        run = subprocess.run([str(wrangler), verb, "--port", "14550"], capture_output=True, text=True, timeout=120)
        assert run.returncode == 1, run.stderr
        assert f"`wrangler {verb}` is part of the simulator" in run.stderr and "robowrangler-sim" in run.stderr
        assert "Traceback" not in run.stderr
    # a board command still works as far as it can without a board: a usage error is a usage error
    bad = subprocess.run([str(wrangler), "spin", "nan"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


def test_host_only_replay_plot_names_the_extra(host_only_venv, tmp_path):
    from robowrangler.recorder.writer import RecordingWriter

    rec = tmp_path / "empty.mcap"
    with RecordingWriter(rec, source="other"):
        pass
    run = subprocess.run([str(host_only_venv / "bin" / "wrangler"), "replay", str(rec), "--plot",
                          str(tmp_path / "out.png")], capture_output=True, text=True, timeout=120)
    assert run.returncode == 1 and "robowrangler[plot]" in run.stderr and "Traceback" not in run.stderr
