"""`analyze --csv`: one row per run and evaluation, every setting a column, readable as is."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
import yaml
from synthetic_study import AT_0, AT_10, FINALS

from sgim_nodes.analysis.cli import main


def _set_parameters(run_dir: Path, **parameters) -> None:
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    meta["parameters"] = {**meta.get("parameters", {}), **parameters}
    (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta))


def test_csv_rows_per_run_and_evaluation_with_every_setting(make_study, tmp_path: Path):
    study = make_study(seeds=3, learners=("sgim-d", "random"))
    for seed in range(3):  # a setting some runs have and others lack, and a path to leave out
        _set_parameters(study / f"sgim-d-seed{seed}", teacher_choice="nearest-unreached",
                        demonstration_period=150, output=f"/x/{seed}", seed=seed)
        _set_parameters(study / f"random-seed{seed}", demonstration_period=150, seed=seed)
    out = tmp_path / "out"
    assert main([str(study), "--out", str(out), "--csv"]) == 0
    with (out / "evaluations.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 * 3 * 3  # learners x seeds x evaluations (0, 10, 20)
    header = list(rows[0])
    assert header[:8] == ["run", "group", "learner", "seed", "finished", "movements_done",
                          "movement", "mean_distance"]
    assert "output" not in header and "teacher_choice" in header
    by_key = {(r["learner"], int(r["seed"]), int(r["movement"])): r for r in rows}
    for learner in ("sgim-d", "random"):
        for seed in range(3):
            expected = {0: AT_0, 10: AT_10[learner][seed], 20: FINALS[learner][seed]}
            for movement, mean in expected.items():
                row = by_key[(learner, seed, movement)]
                assert float(row["mean_distance"]) == pytest.approx(mean)
                assert row["demonstration_period"] == "150"
                assert row["teacher_choice"] == ("nearest-unreached" if learner == "sgim-d"
                                                 else "")


def test_no_csv_unless_asked(study: Path, tmp_path: Path):
    assert main([str(study), "--out", str(tmp_path / "out")]) == 0
    assert not (tmp_path / "out" / "evaluations.csv").exists()
