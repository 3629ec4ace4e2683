"""The learner as a library: `pip install ./sgim_nodes` in a fresh venv without ROS gives the
core, and examples/own_environment.py runs SGIM-D on its own world there.

The venv is made from the base interpreter with no system site-packages and an environment
cleared of everything ros_ws/env.sh sets, so nothing of the ROS workspace can leak in; pip
takes numpy, scipy and tqdm from the package index (at the versions requirements.txt pins, so
they come from pip's cache once ./bootstrap.sh has run). The package is copied first so the
build leaves nothing in the source tree.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
ROS_MODULES = ("rclpy", "sgim_msgs", "sgim_ros", "sim_bridge", "teacher")
# Imports every module of the core, then reports which ROS or node packages came with them.
IMPORT_CORE = f"""
import importlib, pkgutil, sys
import sgim_nodes.core as core
names = [m.name for m in pkgutil.walk_packages(core.__path__, "sgim_nodes.core.")]
for name in names:
    importlib.import_module(name)
leaked = sorted({{m.split(".")[0] for m in sys.modules}} & set({ROS_MODULES!r}))
print(len(names), core.__file__, leaked)
"""

pytestmark = pytest.mark.slow


def clean_env() -> dict[str, str]:
    """The caller's environment without the ROS workspace and the project's venv."""
    drop = ("PYTHON", "AMENT_", "COLCON_", "ROS_", "RMW_", "CMAKE_PREFIX_PATH", "VIRTUAL_ENV",
            "LD_LIBRARY_PATH")
    return {k: v for k, v in os.environ.items() if not k.startswith(drop)}


@pytest.fixture(scope="module")
def plain_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A venv without ROS holding `pip install ./sgim_nodes` (from a copy of the package)."""
    root = tmp_path_factory.mktemp("plain")
    source = root / "sgim_nodes"
    shutil.copytree(REPO / "sgim_nodes", source,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build"))
    # No pip inside: the running pip installs into it (`pip --python`), which saves the
    # ensurepip step; what gets installed is what `pip install ./sgim_nodes` installs.
    venv.EnvBuilder(with_pip=False, system_site_packages=False).create(root / "venv")
    python = root / "venv" / "bin" / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install",
                    "--quiet", "--disable-pip-version-check",
                    "-c", str(REPO / "requirements.txt"), str(source)],
                   check=True, env=clean_env(), cwd=root, timeout=400)
    return python


def run_in(python: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(python), *args], capture_output=True, text=True,
                          env=clean_env(), cwd=python.parent.parent.parent, timeout=300)


def test_venv_has_no_ros(plain_venv: Path) -> None:
    probe = run_in(plain_venv, "-c", "import rclpy")
    assert probe.returncode != 0
    assert "No module named 'rclpy'" in probe.stderr


def test_core_imports_without_ros(plain_venv: Path) -> None:
    result = run_in(plain_venv, "-c", IMPORT_CORE)
    assert result.returncode == 0, result.stderr
    count, path, leaked = result.stdout.split(maxsplit=2)
    assert int(count) >= 15  # every module of core/, not an empty namespace
    assert Path(path).is_relative_to(plain_venv.parent.parent)  # the installed copy
    assert leaked.strip() == "[]"


def test_runner_command_installed(plain_venv: Path) -> None:
    """`learn`, the single-process runner, is on the venv's path and starts without ROS."""
    result = subprocess.run([str(plain_venv.parent / "learn"), "--help"], capture_output=True,
                            text=True, env=clean_env(), timeout=300)
    assert result.returncode == 0, result.stderr
    assert "--learner {sgim-d," in result.stdout


def test_example_learns_on_its_own_world(plain_venv: Path) -> None:
    result = run_in(plain_venv, str(REPO / "examples" / "own_environment.py"),
                    "--movements", "500")
    assert result.returncode == 0, result.stderr
    curve = [(int(n), float(e)) for n, e in
             re.findall(r"after\s+(\d+) movements: mean error ([\d.]+)", result.stdout)]
    assert [n for n, _ in curve] == [0, 250, 500]
    summary = re.search(r"first error ([\d.]+), final error ([\d.]+), (\d+) demonstrations",
                        result.stdout)
    assert summary, result.stdout
    first, final, demonstrations = float(summary[1]), float(summary[2]), int(summary[3])
    assert (first, final) == (curve[0][1], curve[-1][1])
    # The teacher took part (a turn at 0, 150, 300 and 450, each with an unreached goal
    # while the learner is this young) and the learner got much better at its goals.
    assert 1 <= demonstrations <= 4
    assert final < 0.5 * first
