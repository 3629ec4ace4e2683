"""The benchmark's floor, shown beside every learner: how far from what is possible it is.

The floor is the error that a nearest-action lookup on a dense map of the fishing world achieves
on the same benchmark goals, cast with the world's noise (``sim_bridge.data_files.load_floor``,
made by ``python -m sim_bridge.tools.make_floor``). A learner's error minus the floor is what
its exploration and inverse model leave on the table; the floor itself is the world's noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FloorSummary:
    mean: float  # best of k nearest mapped actions, scored on held-back casts (the floor)
    nearest_mean: float  # the single nearest mapped landing's action
    goals: int
    k: int

    def describe(self) -> str:
        return (f"floor {self.mean:.3f}: the best of the {self.k} mapped landings nearest each "
                f"goal, cast again with the world's noise (the nearest one alone: "
                f"{self.nearest_mean:.3f}; {self.goals} goals)")


def benchmark_floor() -> FloorSummary | None:
    """The shipped floor, or None when it is missing or not for the shipped benchmark goals."""
    try:
        from sim_bridge.data_files import load_benchmark_goals, load_floor
        floor, goals = load_floor(), load_benchmark_goals()
    except (ImportError, FileNotFoundError, KeyError):
        return None
    if floor.goals.shape != goals.shape or not np.array_equal(floor.goals, goals):
        return None
    return FloorSummary(floor.mean, floor.nearest_mean, len(goals), floor.k)
