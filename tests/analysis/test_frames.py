"""load_runs (analysis/frames.py): a tidy table of every evaluation and goal, the same from run
folders and from the run tables shipped from them; and the example that draws a page's figure
from it."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pandas as pd
from synthetic_study import EVAL_POINTS, FINALS, PARAMETERS, run_messages, write_run

from sgim_nodes.analysis import load_runs, run_table
from sgim_nodes.analysis.study import load_study
from tests.conftest import REPO


def test_one_row_per_evaluation_and_goal_with_the_settings(study):
    runs = load_runs(study)
    assert len(runs) == 6 * len(EVAL_POINTS) * 2  # 6 runs, 3 evaluations, 2 goals
    assert list(runs.columns[:10]) == ["run", "group", "learner", "seed", "finished",
                                       "movement", "goal", "goal_x", "goal_y", "distance"]
    final = runs[runs.movement == 20].groupby(["learner", "seed"]).distance.mean()
    for learner, values in FINALS.items():
        assert np.allclose(final[learner].to_numpy(), values)
    means = runs.groupby(["run", "movement"]).distance.mean()
    for run in load_study(study, warn=lambda m: None).runs:
        assert np.allclose(means[run.name].to_numpy(), run.eval_mean)
    only = load_runs(study, names=["random-seed1"])
    assert set(only.run) == {"random-seed1"}


def test_shipped_tables_give_the_same_table(study, tmp_path):
    for run in load_study(study, warn=lambda m: None).runs:
        run_table.save_run(run, tmp_path / "shipped" / f"{run.name}.npz", {"behaviour": "b"})
    (tmp_path / "shipped" / "sgim-d-seed0.values.npz").write_bytes(b"not a run table")
    from_folders = load_runs(study).sort_values(["run", "movement", "goal"])
    from_tables = load_runs(tmp_path / "shipped").sort_values(["run", "movement", "goal"])
    pd.testing.assert_frame_equal(from_folders.reset_index(drop=True),
                                  from_tables.reset_index(drop=True))


def test_every_setting_is_a_column(tmp_path):
    write_run(tmp_path / "s", "sgim-d", 0, run_messages("sgim-d", 0, {0: 0.9, 20: 0.2}),
              parameters=PARAMETERS["learner"])
    runs = load_runs(tmp_path / "s")
    assert set(runs.demonstration_period) == {150} and set(runs.imitations) == {5}


def test_the_example_draws_a_page_s_curves_from_run_tables(study, tmp_path, capsys,
                                                           monkeypatch):
    from sgim_nodes.experiments import pinned

    for run in load_study(study, warn=lambda m: None).runs:
        run_table.save_run(run, tmp_path / "shipped" / f"{run.name}.npz", {})
    names = {f"{learner}-seed{seed}": "" for learner in FINALS for seed in range(3)}
    monkeypatch.setattr(pinned.Experiment, "run_fingerprints", lambda self: names)
    example = runpy.run_path(str(REPO / "examples" / "error_curves.py"))
    out = tmp_path / "curves.png"
    assert example["main"](["--experiment", "study", "--data", str(tmp_path / "shipped"),
                            "--out", str(out)]) == 0
    assert out.stat().st_size > 10_000
    said = capsys.readouterr().out
    assert f"sgim-d: {np.mean(FINALS['sgim-d']):.3f} +/- " in said, said
    assert Path(out).read_bytes()[:4] == b"\x89PNG"
