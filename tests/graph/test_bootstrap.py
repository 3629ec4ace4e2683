"""The setup step: clear messages for missing prerequisites, nothing redone when nothing changed."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

from tests.conftest import REPO

BOOTSTRAP = str(REPO / "bootstrap.sh")


def _run(env_extra: dict[str, str]) -> subprocess.CompletedProcess:
    env = dict(os.environ, **env_extra)
    return subprocess.run(
        [BOOTSTRAP], env=env, capture_output=True, text=True, timeout=600, cwd=REPO
    )


def test_missing_python_names_what_to_install():
    result = _run({"SGIM_PYTHON": "python3.11-that-does-not-exist"})
    assert result.returncode == 1
    assert "apt-get install python3.11" in result.stderr


def test_wrong_python_version_is_refused(tmp_path):
    fake = tmp_path / "python-fake"
    fake.write_text('#!/bin/sh\n[ "$1" = --version ] && echo "Python 3.9.2" && exit 0\nexit 1\n')
    fake.chmod(0o755)
    result = _run({"SGIM_PYTHON": str(fake)})
    assert result.returncode == 1
    assert "3.11 exactly" in result.stderr and "3.9.2" in result.stderr


def test_second_run_redoes_nothing():
    first = _run({})
    assert first.returncode == 0, first.stderr[-2000:]
    second = _run({})
    assert second.returncode == 0
    assert "installing" not in second.stderr and "building" not in second.stderr
    assert "ready" in second.stderr


def test_our_modules_bytecode_is_written_even_where_python_writes_none():
    """Node processes read it at every start; with PYTHONDONTWRITEBYTECODE set (as on some
    machines) nothing else writes it."""
    import importlib.util

    sources = [REPO / "sgim_nodes/sgim_nodes/core/learners.py",
               REPO / "sgim_nodes/sgim_nodes/nodes/social_interaction.py",
               REPO / "sim_bridge/sim_bridge/fishing_world.py",
               REPO / "sgim_msgs/sgim_ros/entry.py"]
    Path(importlib.util.cache_from_source(str(sources[0]))).unlink(missing_ok=True)
    result = _run({"PYTHONDONTWRITEBYTECODE": "1"})
    assert result.returncode == 0, result.stderr[-2000:]
    for source in sources:
        cached = Path(importlib.util.cache_from_source(str(source)))
        assert cached.is_file(), f"no bytecode for {source}"
        assert cached.stat().st_mtime >= source.stat().st_mtime, f"stale bytecode: {cached}"


def test_the_venv_packages_have_their_bytecode():
    """pip installs without compiling and bootstrap compiles on every core after: numpy's and
    rclpy's modules, read by every node at start, must have their bytecode."""
    import importlib.util

    for package in ("numpy", "rclpy"):
        source = Path(importlib.util.find_spec(package).origin)
        for module in (source, *sorted(source.parent.glob("*.py"))[:5]):
            cached = Path(importlib.util.cache_from_source(str(module)))
            assert cached.is_file(), f"no bytecode for {module}"
