"""What SGIM-ACTS valued when it chose: each episode's pair values, by replaying a graph run
with the single-process runner.

Why a replay: a run's bag says what the learner chose (the Goal naming a strategy) and asked
(HelpRequest), not the values that made it choose. The runner makes the same movements as the
graph for the same settings and seed (tests/ros/test_graph_runs.py), so replaying the run with
the chooser observed gives those values exactly; the replay's landings are checked against the
run's, movement for movement, before any value is used.

For each episode: the movement count when it was chosen, its strategy, whether its request was
answered with something to learn from, the value (LearnerConfig.strategy_value: gain or
interest) of the chosen pair in the leaf holding its goal, and the autonomous pair's value
there (the learner's own). docs/active_strategies.md's P2 reads them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from sgim_nodes.analysis.run_table import write_arrays
from sgim_nodes.analysis.study import OUTCOME_SIZE, RunData
from sgim_nodes.core.strategies import AUTONOMOUS
from sgim_nodes.experiments.verify import RunnerTwin, first_unequal, landing
from sgim_nodes.sweep.sweep_file import RunSpec

SUFFIX = ".values.npz"
COLUMNS = ("count", "strategy", "answered", "value", "own", "outcome")


class ReplayMismatch(RuntimeError):
    """The replay did not land where the run landed: its values are not the run's."""


def replay(spec: RunSpec) -> dict[str, np.ndarray]:
    """Replay the SGIM-ACTS run of `spec` with its chooser observed (module docstring)."""
    twin = RunnerTwin.of(spec)
    chooser = twin.learner.chooser
    own = next(s for s in chooser.strategies if s.kind == AUTONOMOUS)
    seen: list[tuple[float, float]] = []
    draw = chooser.sample

    def observed(rng: np.random.Generator):
        choice = draw(rng)
        value = (chooser.regions.gain if chooser.value == "gain"
                 else chooser.regions.interest)
        seen.append((value(choice.strategy.name, choice.region),
                     value(own.name, choice.region)))
        return choice

    chooser.sample = observed
    landed: list[list[float]] = []

    def keep(record: dict[str, Any]) -> None:
        if record["type"] == "movement":
            landed.append(landing(record))

    twin.run(keep)
    logs = twin.learner.choices
    return {"count": np.array([c.movement for c in logs], dtype=np.int64),
            "strategy": np.array([c.strategy for c in logs], dtype=str),
            "answered": np.array([bool(c.answered) for c in logs]),
            "value": np.array([v for v, _ in seen], dtype=float),
            "own": np.array([o for _, o in seen], dtype=float),
            "outcome": np.asarray(landed, dtype=float).reshape(-1, OUTCOME_SIZE)}


def check_same_run(values: dict[str, np.ndarray], run: RunData) -> None:
    """ReplayMismatch unless the replay landed where `run` landed, movement for movement."""
    first = first_unequal(values["outcome"], run.outcome)
    if first is not None:
        raise ReplayMismatch(f"{run.name}: the replay's movement {first + 1} is not the run's "
                             f"({len(values['outcome'])} movements replayed, "
                             f"{len(run.outcome)} recorded)")


def values_path(folder: Path, name: str) -> Path:
    return folder / f"{name}{SUFFIX}"


def save(path: Path, values: dict[str, np.ndarray], behaviour: str) -> Path:
    return write_arrays(path, {**values, "behaviour": np.array(behaviour)})


def load(path: Path, behaviour: str) -> dict[str, np.ndarray] | None:
    """The values kept at `path` for a run of `behaviour`; None when absent or another's."""
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data["behaviour"]) != behaviour:
                return None
            return {name: data[name] for name in COLUMNS}
    except (OSError, KeyError, ValueError):
        return None
