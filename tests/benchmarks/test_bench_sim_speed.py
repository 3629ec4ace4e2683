"""bench_sim_speed.py --shared-world: one line per world size, doubling up to the size asked."""

from __future__ import annotations

import re
import subprocess
import sys

from tests.conftest import PYTHON, REPO

sys.path.insert(0, str(REPO / "benchmarks"))


def test_shared_world_times_each_doubling_of_rods():
    from bench_sim_speed import shared_world_steps

    lines = shared_world_steps(5, steps=20)
    counts = [int(re.match(r"\s*(\d+) rods", line).group(1)) for line in lines]
    assert counts == [1, 2, 4]
    per_step = [float(re.search(r"([\d.]+) us per step", line).group(1)) for line in lines]
    assert all(t > 0 for t in per_step)


def test_a_negative_world_size_is_refused():
    done = subprocess.run([PYTHON, str(REPO / "benchmarks" / "bench_sim_speed.py"),
                           "--shared-world", "-1"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "--shared-world" in done.stderr
