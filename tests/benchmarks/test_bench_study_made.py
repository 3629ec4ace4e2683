"""bench_study.py --made: the efficiency of an experiment's runs made already, from their
logs' cast counts and their metadata's spans."""

from __future__ import annotations

import subprocess

import pytest
import yaml

from tests.benchmarks.scripts import load_benchmark
from tests.conftest import PYTHON, REPO

SCRIPT = REPO / "benchmarks" / "bench_study.py"


def load_bench():
    return load_benchmark("bench_study")


def test_busy_time_counts_overlaps_once_and_skips_pauses():
    busy = load_bench().busy_seconds
    assert busy([]) == 0
    assert busy([(0, 10), (5, 12), (20, 25)]) == 17  # 0-12 and 20-25
    assert busy([(0, 10), (2, 3)]) == 10  # one inside the other


def run_folder(root, name, start, end, movements, evaluator_casts, teacher_casts=None,
               outcome="finished"):
    folder = root / name
    (folder / "logs").mkdir(parents=True)
    (folder / "metadata.yaml").write_text(yaml.safe_dump({
        "started": f"2026-12-04T10:{start:02d}:00+00:00",
        "ended": f"2026-12-04T10:{end:02d}:00+00:00", "outcome": outcome,
        "movements_done": movements}))
    (folder / "logs" / "evaluator.log").write_text(
        "evaluation at 0: casts made 10, kept 0 in all\n"
        f"evaluation at 100: casts made {evaluator_casts}, kept 3 in all\n")
    if teacher_casts is not None:
        (folder / "logs" / "teacher.log").write_text(
            f"run finished: 2 demonstrations (casts made {teacher_casts}, kept 1)\n")


@pytest.mark.slow  # measures one cast's CPU: 60 casts in the fishing world
def test_made_sums_every_finished_runs_casts_over_its_busy_time(tmp_path):
    run_folder(tmp_path, "a", 0, 10, 100, 40, 7)
    run_folder(tmp_path, "b", 5, 15, 200, 60)
    run_folder(tmp_path, "c", 30, 40, 300, 80)
    run_folder(tmp_path, "failed", 0, 50, 50, 1000, outcome="failed")
    out = subprocess.run([PYTHON, str(SCRIPT), "--made", str(tmp_path)], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert "3 finished runs" in out.stdout
    # casts: movements 600, evaluator 180, teacher 7; busy: 0-15 and 30-40 minutes = 25 min
    assert "casts 787 " in out.stdout, out.stdout
    assert "wall 0.42 h" in out.stdout and "run time 0.50 h" in out.stdout, out.stdout


def test_made_refuses_a_folder_without_runs(tmp_path):
    out = subprocess.run([PYTHON, str(SCRIPT), "--made", str(tmp_path / "none")],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "no folder" in out.stderr
    out = subprocess.run([PYTHON, str(SCRIPT), "--made", str(tmp_path)], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode != 0 and "no finished graph run" in out.stderr
