"""The named Markdown blocks the pages show are those of results.md (one source)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from synthetic_study import fingerprint

from sgim_nodes.analysis import cli
from sgim_nodes.analysis.floor import FloorSummary
from sgim_nodes.analysis.pooling import MixedRunsError
from sgim_nodes.analysis.report import (
    BLOCKS,
    CURVE_POINTS,
    blocks,
    curve_points,
    error_curve_table,
    pairwise_table,
)
from sgim_nodes.analysis.statistics import Curve
from sgim_nodes.analysis.study import load_study

FLOOR = FloorSummary(mean=0.07, nearest_mean=0.1, goals=129, k=3)


def test_results_md_is_made_of_the_blocks(study: Path, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(cli, "benchmark_floor", lambda: FLOOR)
    out = tmp_path / "out"
    assert cli.main([str(study), "--out", str(out)]) == 0
    md = (out / "results.md").read_text()
    found = blocks(load_study(study), FLOOR)
    assert tuple(found) == BLOCKS
    for name, text in found.items():
        assert text and text in md, name


def test_the_blocks_of_the_synthetic_study(study: Path) -> None:
    found = blocks(load_study(study), FLOOR)
    final = found["final-errors"].splitlines()
    assert final[0] == ("| learner | n | demonstrations per run | mean final error (movement 20) "
                        "| 95 % interval | above the floor | per seed |")
    assert final[2].startswith("| sgim-d | 3 | 0 | **0.250** | [0.126, 0.374] | 0.180 | "
                               "0.200, 0.250, 0.300 |")
    assert final[-1].startswith("| floor (map lookup) |")
    # Evaluated at 0, 10 and 20 only: the columns are the counts the runs have, but 0.
    curve = found["error-curve"].splitlines()
    assert curve[0] == "| movements | 10 | 20 |"
    assert curve[2] == "| sgim-d | **0.420** | **0.250** |"
    pairwise = found["pairwise"].splitlines()
    assert "| n (a, b) |" in pairwise[0] and "| MW p (Holm) | smallest MW p |" in pairwise[0]
    assert pairwise[2].startswith("| sgim-d | random | 3, 3 | -0.317 [-0.473, -0.161] | "
                                  "sgim-d | 0.0061 | 0.012 | -1.00 [-1.00, -0.27] | 0.1 | "
                                  "0.1 | 0.1 | no |")
    assert "Holm's correction over the 2 p-values" in found["pairwise"]
    coverage = found["isolated-coverage"].splitlines()
    assert coverage[2].startswith("| sgim-d | 1/3 | 3, 0, 0 | 2, 0, 0 | 5, never, never | 5 |")
    assert coverage[3].startswith("| random | 0/3 | 0, 0, 0 | the same |")
    assert "| smallest Fisher p |" in found["isolated-tests"].splitlines()[0]


def _curve(name: str, movements: np.ndarray, mean: np.ndarray) -> Curve:
    nan = np.full(len(movements), np.nan)
    return Curve(name, movements, mean, nan, nan, np.full(len(movements), 10))


def test_the_error_curve_block_shows_the_usual_movement_counts() -> None:
    moves = np.arange(0, 5001, 250)
    curves = {"sgim-d": _curve("sgim-d", moves, 0.2 - moves / 50000),
              "demo-only": _curve("demo-only", moves, 0.3 - moves / 20000)}
    assert curve_points(curves) == list(CURVE_POINTS)
    lines = error_curve_table(curves).splitlines()
    assert lines[0] == "| movements | " + " | ".join(map(str, CURVE_POINTS)) + " |"
    # sgim-d is lower up to 3000 movements, demo-only after.
    assert lines[2].startswith("| sgim-d | **0.195** | **0.190** | **0.180** |")
    assert lines[2].endswith("| **0.140** | 0.120 | 0.100 |")
    assert lines[3].endswith("| 0.150 | **0.100** | **0.050** |")
    # A point a learner lacks is left empty; a tie (as shown) bolds both.
    assert error_curve_table(curves, [250, 300]).splitlines()[2] == "| sgim-d | **0.195** |  |"
    level = {k: _curve(k, np.array([10]), np.array([v])) for k, v in (("a", 0.1), ("b", 0.1))}
    assert error_curve_table(level).splitlines()[2:] == ["| a | **0.100** |", "| b | **0.100** |"]


def test_a_pairwise_table_of_any_groups_for_other_reports() -> None:
    groups = {"sgim-d": [0.05, 0.06, 0.055, 0.052, 0.058],
              "saggriac": [0.09, 0.1, 0.095, 0.12, 0.085], "random": [0.1, 0.13, 0.12, 0.11]}
    text = pairwise_table(groups, [("sgim-d", "saggriac"), ("sgim-d", "random")])
    rows = [line for line in text.splitlines() if line.startswith("| sgim-d |")]
    assert len(rows) == 2 and "| 5, 5 |" in rows[0] and "| 5, 4 |" in rows[1]
    assert "over the 4 p-values" in text
    assert "| 0.0079 |" in rows[0]  # the smallest exact MW p with 5 against 5


def test_blocks_refuse_mixed_runs_unless_allowed(make_study) -> None:
    study = load_study(make_study(fingerprints={"sgim-d-seed0": fingerprint(world="w2")}))
    with pytest.raises(MixedRunsError, match="world: 3071d000 in 5 runs"):
        blocks(study)
    assert set(blocks(study, allow_mixed=True)) >= {"final-errors", "pairwise"}
