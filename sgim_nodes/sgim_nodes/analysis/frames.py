"""Runs as a tidy pandas table: one row per evaluation and benchmark goal, every setting a
column, read from run folders or from the run tables the repository ships.

Why tidy: a scientist's own statistics start from one flat table that any tool groups by any
setting; the mean error of an evaluation is a ``groupby`` away, and so is any subset of goals.

    from sgim_nodes.analysis import load_runs
    runs = load_runs("experiments/shipped")                  # or a study's runs folder
    final = runs[runs.movement == runs.movement.max()]
    final.groupby(["group", "run"]).distance.mean().groupby("group").describe()

Columns: ``run``, ``group`` (the learner, or the learner and the settings that set it apart:
study.group_runs), ``learner``, ``seed``, ``finished``, ``movement`` (the learner's movement
count the evaluation reflects), ``goal`` (the goal's index in the benchmark set), ``goal_x``,
``goal_y`` (outcome units, [-1, 1]), ``distance`` (from the goal to where the learner's cast
for it landed, outcome units), then every parameter of the run that can change what it does
(analysis/export.settings_of), under its own name. A setting a run did not have is empty.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from sgim_nodes.analysis.export import settings_of
from sgim_nodes.analysis.run_table import load_run
from sgim_nodes.analysis.study import RunData, discover_runs, group_runs, load_run_data

IDENTITY = ("run", "group", "learner", "seed", "finished", "movement", "goal", "goal_x",
            "goal_y", "distance")
TABLE_SUFFIX = ".npz"
NOT_TABLES = (".values.npz",)  # what else may lie beside the run tables


def find_runs(path: str | Path, names: Iterable[str] | None = None) -> list[RunData]:
    """The runs at `path`: a run folder, a run table, or a folder of either (both may mix);
    only those called `names` when given. FileNotFoundError when `path` does not exist."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such run, run table or folder")
    wanted = None if names is None else set(names)
    if path.is_file():
        runs = [load_run(path)]
    else:
        tables = sorted(p for p in path.glob(f"*{TABLE_SUFFIX}")
                        if not p.name.endswith(NOT_TABLES))
        if wanted is not None:
            tables = [p for p in tables if p.name[:-len(TABLE_SUFFIX)] in wanted]
        runs = [load_run(p) for p in tables]
        for folder in discover_runs(path):
            if wanted is None or folder.name in wanted:
                run = load_run_data(folder, warn=lambda message: None)
                if run is not None:
                    runs.append(run)
    return [r for r in runs if wanted is None or r.name in wanted]


def runs_frame(runs: Sequence[RunData]) -> pd.DataFrame:
    """The tidy table of `runs` (module docstring); runs are grouped as the analysis groups
    them."""
    group_runs(list(runs), warn=lambda message: None)
    parts = []
    for run in runs:
        evaluations, goals = run.eval_distances.shape if run.eval_distances.ndim == 2 else (0, 0)
        if not evaluations or not goals:
            continue
        points = run.eval_goals.reshape(goals, -1)
        frame = pd.DataFrame({
            "run": run.name, "group": run.group, "learner": run.learner, "seed": run.seed,
            "finished": run.finished,
            "movement": np.repeat(run.eval_index, goals),
            "goal": np.tile(np.arange(goals), evaluations),
            "goal_x": np.tile(points[:, 0], evaluations),
            "goal_y": np.tile(points[:, 1], evaluations),
            "distance": run.eval_distances.ravel()})
        for name, value in settings_of(run).items():
            frame[name] = value
        parts.append(frame)
    if not parts:
        return pd.DataFrame(columns=list(IDENTITY))
    table = pd.concat(parts, ignore_index=True)
    settings = sorted(set(table.columns) - set(IDENTITY))
    return table[[*IDENTITY, *settings]]


def load_runs(path: str | Path, names: Iterable[str] | None = None) -> pd.DataFrame:
    """The tidy table of the runs at `path` (find_runs, runs_frame)."""
    return runs_frame(find_runs(path, names))
