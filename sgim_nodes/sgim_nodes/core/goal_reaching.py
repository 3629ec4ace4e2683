"""One goal attempt as an ask/tell object, driven movement by movement.

Exploration against exploitation keeps the paper's rule: the probability of exploring grows
with the distance d from the goal to the closest outcome reached so far (min(cap, gain * d /
box side)). But exploring no longer means one uniform random action (that is motor babbling,
the ``random`` learner): it perturbs the best-known action for the goal (the inverse model's)
with Gaussian noise whose width in action units grows with d, so the learner searches just
beyond what it knows, widely only where it knows nothing near. An exploring attempt is that
single movement ("exploration").

Otherwise ("goal_directed") the inverse model gives the first action and an optimiser refines
it on real movements (refinement.py) until an outcome lands within ``reach_threshold`` of the
goal or ``goal_budget`` movements are spent.

The caller stores every successful movement in memory BEFORE calling ``observe`` (the
local-linear refinement fits on memory); a failed movement counts against the budget and costs
``failure_cost``. ``start_distance`` is memory's distance to the goal before the attempt:
the competence is measured against it (competence.py).
"""

from __future__ import annotations

import math

import numpy as np

from . import portable
from .competence import start_distance
from .config import Distances, LearnerConfig
from .environment import ResultLike, is_success
from .inverse_model import InverseEstimate, InverseModel
from .memory import Memory
from .refinement import (
    LocalLinearSearch,
    NelderMeadSearch,
    ProbeScale,
    RandomSearch,
    SubspaceSearch,
)
from .scale import WorldScale

PROBES = 0
EXPLORATION = "exploration"
GOAL_DIRECTED = "goal_directed"


def exploration_probability(closest_distance: float, gain: float, cap: float,
                            size: float = 1.0) -> float:
    """min(cap, gain * distance / size); 1 when nothing was reached yet (no inverse model)."""
    if not math.isfinite(closest_distance):
        return 1.0
    return float(min(cap, gain * closest_distance / size))


def probe_scale_for(config: LearnerConfig, scale: WorldScale, action_dim: int) -> ProbeScale:
    """The learner's probe-size estimate (refinement.ProbeScale), in Euclidean action units."""
    root = math.sqrt(action_dim)
    return ProbeScale(scale.noise, config.trust_radius_action * root, 0.01 * root, 0.5 * root)


def exploration_width(closest_distance: float, full_width: float,
                      full_distance: float) -> float:
    """Standard deviation (action units) of an exploration's perturbation: proportional to
    the distance to the reached set, full_width from full_distance on."""
    return float(full_width * min(1.0, closest_distance / full_distance))


class GoalAttempt:
    """Ask/tell: ``next_action()`` then ``observe(action, result)`` until ``done``."""

    def __init__(self, goal: np.ndarray, memory: Memory, inverse_model: InverseModel,
                 config: LearnerConfig, scale: WorldScale, rng: np.random.Generator,
                 action_dim: int, probe_scale: ProbeScale | None = None) -> None:
        self.goal = np.asarray(goal, dtype=float)
        self.memory = memory
        self.inverse_model = inverse_model
        self.config = config
        self.distances: Distances = config.distances(scale)
        self.rng = rng
        self.action_dim = action_dim
        self.probe_scale = probe_scale
        closest = memory.closest_distance(self.goal)
        self.start_distance = start_distance(closest, self.goal, scale.centre)
        self.p_explore = exploration_probability(closest, config.explore_gain,
                                                 config.explore_cap, scale.size)
        self.explore = bool(rng.random() < self.p_explore)
        self._closest = closest
        self.movements = 0
        self._since_best = 0
        self.best_distance = float("inf")
        self.best_outcome: np.ndarray | None = None
        self.done = False
        self._estimate: InverseEstimate | None = inverse_model.estimate(self.goal)
        self._search: LocalLinearSearch | RandomSearch | NelderMeadSearch | None = None

    @property
    def label(self) -> str:
        return EXPLORATION if self.explore else GOAL_DIRECTED

    def next_action(self) -> tuple[np.ndarray, str]:
        if self.done:
            raise RuntimeError("goal attempt is finished")
        est = self._estimate
        if est is None:  # empty memory: nothing to perturb or refine, motor babbling it is
            self.explore = True
            return self.rng.uniform(-1.0, 1.0, self.action_dim), EXPLORATION
        if self.explore:
            width = exploration_width(self._closest, self.config.explore_action,
                                      self.distances.explore_distance)
            action = est.action + self.rng.normal(0.0, width, self.action_dim)
            return np.clip(action, -1.0, 1.0), EXPLORATION
        if self._search is None:
            return est.action.copy(), GOAL_DIRECTED
        return self._search.ask(), GOAL_DIRECTED

    def _new_search(self, action: np.ndarray, outcome, cost: float):
        c = self.config
        radius = c.trust_radius_action * math.sqrt(self.action_dim)
        if c.optimiser == "subspace":
            probe = radius if self.probe_scale is None else self.probe_scale.radius()
            return SubspaceSearch(self.goal, action, outcome, cost, probe, PROBES or len(self.goal),
                                  self.rng, self.probe_scale)
        if c.optimiser == "local-linear":
            return LocalLinearSearch(self.goal, self.memory, action, cost, radius,
                                     c.local_neighbours, self.rng)
        if c.optimiser == "random-search":
            return RandomSearch(action, cost, c.trust_radius_action, self.rng)
        return NelderMeadSearch(self.goal, self.memory, action, cost, c.nm_initial_step)

    def observe(self, action: np.ndarray, result: ResultLike) -> None:
        """Report the result of the last action (after the caller stored it in memory)."""
        self.movements += 1
        self._since_best += 1
        outcome = None
        if is_success(result):
            outcome = np.asarray(result.outcome, dtype=float)
            cost = portable.norm(outcome - self.goal)
            if cost < self.best_distance:
                self.best_distance, self.best_outcome = cost, outcome.copy()
                self._since_best = 0
        else:
            cost = self.distances.failure_cost
        if self.explore:
            self.done = True
            return
        if self._search is None:
            self._search = self._new_search(action, outcome, cost)
        elif isinstance(self._search, SubspaceSearch):
            self._search.tell_outcome(action, outcome, cost)
        else:
            self._search.tell(action, cost)
        if (self.best_distance < self.distances.reach_threshold
                or self.movements >= self.config.goal_budget
                or self._since_best >= self.config.attempt_patience):
            self.done = True
