"""The benchmark's floor beside every learner in `analyze`'s tables, JSON and error curves."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sgim_nodes.analysis import cli
from sgim_nodes.analysis.floor import FloorSummary, benchmark_floor
from sim_bridge import data_files


def test_the_shipped_floor_is_found_for_the_shipped_goals() -> None:
    floor = benchmark_floor()
    assert floor is not None
    shipped = data_files.load_floor()
    assert floor.mean == pytest.approx(shipped.mean)
    assert floor.goals == len(data_files.load_benchmark_goals()) and floor.k == shipped.k
    assert 0.0 < floor.mean <= floor.nearest_mean + 0.05


def test_a_floor_of_other_goals_is_not_shown(monkeypatch: pytest.MonkeyPatch) -> None:
    real = data_files.load_floor()
    moved = data_files.Floor(goals=real.goals + 0.01, per_goal=real.per_goal,
                             nearest=real.nearest, k=real.k, choose_casts=real.choose_casts,
                             score_casts=real.score_casts)
    monkeypatch.setattr(data_files, "load_floor", lambda: moved)
    assert benchmark_floor() is None


@pytest.mark.slow
def test_report_shows_each_learner_above_the_floor(study: Path, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    floor = FloorSummary(mean=0.07, nearest_mean=0.1, goals=129, k=3)
    monkeypatch.setattr(cli, "benchmark_floor", lambda: floor)
    out = tmp_path / "out"
    assert cli.main([str(study), "--out", str(out)]) == 0
    md = (out / "results.md").read_text()
    assert "above the floor" in md and "| floor (map lookup) |  |  | 0.070 |" in md
    final = md.split("## Final error")[1].split("## ")[0]
    row = next(line for line in final.splitlines() if line.startswith("| sgim-d |"))
    assert "| **0.250** |" in row and "| 0.180 |" in row  # 0.25 (the lowest) - 0.07
    results = json.loads((out / "results.json").read_text())
    assert results["floor"]["mean"] == pytest.approx(0.07)


def test_report_without_a_floor(study: Path, tmp_path: Path,
                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(cli, "benchmark_floor", lambda: None)
    out = tmp_path / "out"
    assert cli.main([str(study), "--out", str(out)]) == 0
    md = (out / "results.md").read_text()
    assert "above the floor" not in md and "floor (map lookup)" not in md
    assert json.loads((out / "results.json").read_text())["floor"] is None
    assert np.isfinite(json.loads((out / "results.json").read_text())["final_errors"]["sgim-d"]
                       ["mean"])
