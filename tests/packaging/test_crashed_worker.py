"""A test worker that dies never hangs the suite (tests/scheduling.py).

A child pytest runs a small suite through the project's scheduler, in which one test kills
its own worker with SIGSEGV between two ordinary tests of its file. Whatever the worker count,
the run must end by itself, fail that test by name with the signal, and still run every other
test, the ones after it in its file included.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

CONFTEST = f"""
import sys

import pytest

sys.path.insert(0, {str(REPO)!r})


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    from tests.scheduling import make_scheduler

    return make_scheduler(config, log)


@pytest.hookimpl(optionalhook=True)
def pytest_handlecrashitem(crashitem, report, sched):
    from tests.conftest import pytest_handlecrashitem

    pytest_handlecrashitem(crashitem, report, sched)
"""

DYING = """
import os
import signal


def test_before():
    pass


def test_dies():
    os.kill(os.getpid(), signal.SIGSEGV)


def test_after():
    pass
"""

ORDINARY = """
def test_one():
    pass


def test_two():
    pass
"""


@pytest.mark.parametrize("workers", [1, 2, 4])
def test_a_crashed_worker_fails_its_test_and_the_run_ends(tmp_path: Path, workers: int) -> None:
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "conftest.py").write_text(textwrap.dedent(CONFTEST))
    (tmp_path / "test_dying.py").write_text(DYING)
    for index in range(6):
        (tmp_path / f"test_ordinary_{index}.py").write_text(ORDINARY)
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    try:
        done = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:randomly",
             "-n", str(workers), "-rf", str(tmp_path)],
            cwd=tmp_path, env=env, capture_output=True, text=True, timeout=180)
    except subprocess.TimeoutExpired as hung:
        pytest.fail(f"the child suite hung with {workers} worker(s):\n{hung.stdout}")
    out = done.stdout
    assert done.returncode == 1, out + done.stderr
    assert "1 failed, 14 passed" in out, out
    assert "FAILED test_dying.py::test_dies" in out, out
    assert "killed by SIGSEGV" in out, out
