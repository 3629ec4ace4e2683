"""One goal attempt as an ask/tell object, driven movement by movement.

Exploration against exploitation (issue 4, point 6): with probability proportional to the
distance between the goal and the closest outcome reached so far (capped), the attempt is a
single random action ("exploration"): far from everything known the inverse model has nothing
to interpolate, near known outcomes it is worth refining.  Otherwise the inverse model gives
the first action and Nelder-Mead refines it on real movements ("goal_directed") until the goal
is reached within ``reach_threshold`` or ``goal_budget`` movements are spent.

The caller stores every successful movement in memory; a failed movement counts against the
budget and is told to Nelder-Mead as ``failure_cost``.
"""

from __future__ import annotations

import numpy as np

from .config import LearnerConfig
from .environment import ResultLike, is_success
from .inverse_model import InverseEstimate, InverseModel
from .memory import Memory
from .nelder_mead import AskTellNelderMead

EXPLORATION = "exploration"
GOAL_DIRECTED = "goal_directed"


def exploration_probability(closest_distance: float, gain: float, cap: float) -> float:
    """min(cap, gain * distance); 1 when nothing was reached yet (no inverse model exists)."""
    if not np.isfinite(closest_distance):
        return 1.0
    return float(min(cap, gain * closest_distance))


class GoalAttempt:
    """Ask/tell: ``next_action()`` then ``observe(action, result)`` until ``done``."""

    def __init__(self, goal: np.ndarray, memory: Memory, inverse_model: InverseModel,
                 config: LearnerConfig, rng: np.random.Generator, action_dim: int) -> None:
        self.goal = np.asarray(goal, dtype=float)
        self.memory = memory
        self.inverse_model = inverse_model
        self.config = config
        self.rng = rng
        self.action_dim = action_dim
        self.p_explore = exploration_probability(memory.closest_distance(self.goal),
                                                 config.explore_gain, config.explore_cap)
        self.explore = bool(rng.random() < self.p_explore)
        self.movements = 0
        self.best_distance = float("inf")
        self.best_outcome: np.ndarray | None = None
        self.done = False
        self._estimate: InverseEstimate | None = None
        self._nm: AskTellNelderMead | None = None
        self._simplex: tuple[np.ndarray, list[float | None]] | None = None

    @property
    def label(self) -> str:
        return EXPLORATION if self.explore else GOAL_DIRECTED

    def next_action(self) -> tuple[np.ndarray, str]:
        if self.done:
            raise RuntimeError("goal attempt is finished")
        if self.explore:
            return self.rng.uniform(-1.0, 1.0, self.action_dim), EXPLORATION
        if self._nm is not None:
            return self._nm.ask(), GOAL_DIRECTED
        if self._estimate is None:
            self._estimate = self.inverse_model.estimate(self.goal)
            if self._estimate is None:  # empty memory: cannot exploit, explore instead
                self.explore = True
                return self.next_action()
            self._simplex = self._initial_simplex(self._estimate)
        return self._estimate.action.copy(), GOAL_DIRECTED

    def _initial_simplex(self, est: InverseEstimate) -> tuple[np.ndarray, list[float | None]]:
        """Vertices after the inverse model's action: the interpolated neighbours, then the
        goal's next nearest memory pairs (their cost is known: no movement needed), then, only
        if memory is too small, the action plus nm_initial_step along coordinate axes."""
        mem, need = self.memory, self.action_dim  # + the inverse action itself = dim + 1
        chosen: list[int] = []
        for i in list(est.neighbour_indices) + list(mem.nearest(self.goal, need + 1)[1]):
            if int(i) not in chosen:
                chosen.append(int(i))
            if len(chosen) == need:
                break
        verts = [mem.actions[i].copy() for i in chosen]
        values: list[float | None] = [
            float(np.linalg.norm(mem.outcomes[i] - self.goal)) for i in chosen]
        axis = 0
        while len(verts) < need:
            v = est.action.copy()
            step = self.config.nm_initial_step
            v[axis % self.action_dim] += step if v[axis % self.action_dim] + step <= 1 else -step
            verts.append(v)
            values.append(None)
            axis += 1
        return np.array(verts), values

    def observe(self, action: np.ndarray, result: ResultLike) -> None:
        """Report the result of the last action (after the caller stored it in memory)."""
        self.movements += 1
        if is_success(result):
            outcome = np.asarray(result.outcome, dtype=float)
            cost = float(np.linalg.norm(outcome - self.goal))
            if cost < self.best_distance:
                self.best_distance, self.best_outcome = cost, outcome.copy()
        else:
            cost = self.config.failure_cost
        if self.explore:
            self.done = True
            return
        if self._nm is None:
            assert self._simplex is not None
            verts, values = self._simplex
            self._nm = AskTellNelderMead(np.vstack([action, verts]), [cost, *values])
        else:
            self._nm.tell(cost)
        if (self.best_distance < self.config.reach_threshold
                or self.movements >= self.config.goal_budget):
            self.done = True
