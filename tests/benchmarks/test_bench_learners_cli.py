"""bench_learners.py's command line: the seeds it runs and its refusals of bad input."""

from __future__ import annotations

import json
import subprocess

import pytest

from tests.conftest import PYTHON, REPO

pytestmark = pytest.mark.slow  # each test runs the benchmark script: seconds each

SCRIPT = str(REPO / "benchmarks" / "bench_learners.py")


def test_first_seed_runs_the_seeds_after_it(tmp_path):
    out = tmp_path / "runs.json"
    subprocess.run([PYTHON, SCRIPT, "--worlds", "arm-7", "--learners", "random", "--seeds", "2",
                    "--first-seed", "3", "--movements", "60", "--eval-every", "30",
                    "--goals", "validation", "--jobs", "1", "--json", str(out)],
                   check=True, capture_output=True, timeout=300)
    runs = json.loads(out.read_text())["runs"]
    assert sorted(r["seed"] for r in runs) == [3, 4]


def test_fishing_has_validation_goals_apart_from_its_benchmark():
    """Fishing choices are judged on other points of the benchmark's cells, never on its goals;
    no floor is shipped for them (NaN, not the benchmark's)."""

    import numpy as np

    from sgim_nodes.experiments.runner_jobs import floor, goals_for

    _, benchmark = goals_for("fishing", "benchmark")
    _, validation = goals_for("fishing", "validation")
    assert validation.shape == benchmark.shape
    assert np.min(np.linalg.norm(validation[:, None] - benchmark[None], axis=2)) > 0
    assert np.isnan(floor("fishing", "validation")[0])
    assert np.isfinite(floor("fishing", "benchmark")[0])


def test_bad_counts_are_refused_with_a_message():
    for argv in (["--seeds", "0"], ["--first-seed", "-1"], ["--jobs", "0"]):
        done = subprocess.run([PYTHON, SCRIPT, *argv], capture_output=True, text=True,
                              timeout=60)
        assert done.returncode == 2 and "must be >= 1" in done.stderr, argv


def test_mode1_shares_are_printed_only_for_learners_with_mode_1():
    """random-goals draws no mode-1 goal: no share line for it, no NaN, no numpy warning;
    a frame in which no run drew one is a dash, not a mean of nothing."""

    import numpy as np

    proc = subprocess.run([PYTHON, "-W", "error::RuntimeWarning", SCRIPT, "--worlds", "arm-7",
                           "--learners", "random-goals", "saggriac", "--seeds", "1",
                           "--movements", "600", "--eval-every", "300", "--goals",
                           "validation", "--jobs", "1"],
                          check=True, capture_output=True, text=True, timeout=300)
    lines = [ln for ln in proc.stdout.splitlines() if "mode-1 goals in never-reachable" in ln]
    assert len(lines) == 1, proc.stdout  # SAGG-RIAC's only
    lower_level = proc.stdout.split("lower level and interest")[1]
    assert "nan" not in lower_level
    from sgim_nodes.experiments.reports.learners import frame_means

    nan = float("nan")
    assert frame_means(np.array([[nan, nan], [nan, nan]])) is None
    got = frame_means(np.array([[0.5, nan, nan], [0.25, 1.0, nan]]))
    assert got[:2].tolist() == [0.375, 1.0] and np.isnan(got[2])
