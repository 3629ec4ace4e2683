"""`analyze --csv`: one row per run and evaluation, every setting a column.

Why: pandas (or R, or a spreadsheet) users want the study's raw numbers in one flat table, to
do their own statistics, without reading bags: ``pd.read_csv("evaluations.csv")`` then group
by any setting. The columns are the run's identity (run, group, learner, seed, finished), the
evaluation (movement, mean_distance), then every parameter of the run's metadata except paths
and per-run plumbing (``study.PER_RUN``), under its own name; a setting a run did not have is
left empty.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

from sgim_nodes.analysis.study import PER_RUN, Study

IDENTITY = ("run", "group", "learner", "seed", "finished", "movements_done", "movement",
            "mean_distance")


def _cell(value: Any) -> Any:
    """Lists and mappings as one readable cell; everything else as it is."""
    if isinstance(value, list | tuple):
        return " ".join(map(str, value))
    if isinstance(value, dict):
        return ";".join(f"{k}={v}" for k, v in value.items())
    return value


def settings_of(run) -> dict[str, Any]:
    params = run.metadata.get("parameters")
    params = params if isinstance(params, dict) else {}
    found = {k: _cell(v) for k, v in params.items() if k not in PER_RUN and k not in IDENTITY}
    if "teacher" in run.metadata:
        found["teacher"] = run.metadata["teacher"]
    return found


def evaluation_rows(study: Study) -> list[dict[str, Any]]:
    rows = []
    for run in study.runs:
        settings = settings_of(run)
        for movement, mean in zip(run.eval_index, run.eval_mean, strict=True):
            rows.append({"run": run.name, "group": run.group, "learner": run.learner,
                         "seed": run.seed, "finished": run.finished,
                         "movements_done": run.movements_done, "movement": int(movement),
                         "mean_distance": float(mean), **settings})
    return rows


def write_csv(study: Study, path: Path) -> Path:
    rows = evaluation_rows(study)
    settings = sorted({k for row in rows for k in row} - set(IDENTITY))
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=[*IDENTITY, *settings], restval="")
        writer.writeheader()
        writer.writerows(rows)
    return path
