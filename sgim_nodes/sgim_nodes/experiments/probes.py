"""Probes that look inside a goal-babbling learner while it runs, for the learner benchmarks.

They answer the questions of issue 10 with measurements rather than final errors alone:
- does a goal attempt gain on memory (end closer to its goal than memory's closest outcome
  was before it)? On the arms also without noise: a stored outcome is the luckiest of many
  noisy casts near the goal, so its noisy distance flatters memory;
- how often does the learner explore, and how far from what it knows are its goals?
- is the interest signal or noise (real interest against the interest of each leaf's window
  in shuffled order)?
- do mode-1 goals avoid space that no movement can reach?
Nothing here changes what the learner does: the probe only reads the finished processes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from sgim_nodes.core import portable
from sgim_nodes.core.goal_reaching import GoalAttempt
from sgim_nodes.core.imitation import Imitation
from sgim_nodes.core.learners import GoalBabblingLearner
from sgim_nodes.core.region_tree import interest


@dataclass
class AttemptRecord:
    movement: int  # the learner's movement count when the attempt ended
    mode: int  # goal mode (1, 2, 3), 4 for a demonstration's imitation
    goal: np.ndarray
    explore: bool
    start_distance: float
    best_distance: float
    movements: int
    competence: float
    true_start: float = float("nan")  # noise-free distances (analytic worlds only)
    true_best: float = float("nan")


@dataclass
class Probe:
    """Attach to a GoalBabblingLearner; records every finished attempt and imitation."""

    learner: GoalBabblingLearner
    forward: Callable[[np.ndarray], np.ndarray] | None = None
    """The world's noise-free forward model, if it has one (the arms): then every attempt is
    also measured without noise, from memory's closest pair's ACTION before the attempt to the
    attempt's best action, free of the luck a stored noisy outcome carries."""
    attempts: list[AttemptRecord] = field(default_factory=list)

    def __post_init__(self) -> None:
        original = self.learner._record_competence
        original_new = self.learner._new_process
        learner = self.learner
        forward = self.forward
        tracked: dict[int, list] = {}  # id(attempt) -> [start action, best action, best cost]

        def new_process() -> GoalAttempt | Imitation:
            process = original_new()
            if forward is not None and isinstance(process, GoalAttempt) and len(learner.memory):
                _, rows = learner.memory.nearest(process.goal, 1)
                start = learner.memory.actions[int(np.ravel(rows)[0])].copy()
                tracked[id(process)] = [start, None, float("inf")]
                observe = process.observe

                def observe_and_track(action, result, process=process, observe=observe):
                    before = process.best_distance
                    observe(action, result)
                    if process.best_distance < before:
                        tracked[id(process)][1] = np.asarray(action, float).copy()
                process.observe = observe_and_track  # type: ignore[method-assign]
            return process

        def record(process: GoalAttempt | Imitation) -> float:
            comp = original(process)
            is_attempt = isinstance(process, GoalAttempt)
            true_start = true_best = float("nan")
            track = tracked.pop(id(process), None)
            if track is not None and track[1] is not None:
                goal = np.asarray(process.goal, float)
                true_start = portable.norm(forward(track[0]) - goal)
                true_best = portable.norm(forward(track[1]) - goal)
            self.attempts.append(AttemptRecord(
                learner.n_movements, learner.last_goal_mode if is_attempt else 4,
                np.asarray(process.goal, float).copy(), is_attempt and process.explore,
                float(process.start_distance), float(process.best_distance),
                process.movements, comp, true_start, true_best))
            return comp

        learner._record_competence = record  # type: ignore[method-assign]
        learner._new_process = new_process  # type: ignore[method-assign]

    def summary(self, frame: int, total: int, unreachable: ReachMap | None) -> dict:
        """Gain on memory is start distance - best distance of the goal-directed attempts that
        landed at least once (those with every movement failed are counted apart), over all of
        them and over those whose goal lies in reachable space."""
        goal_attempts = [a for a in self.attempts if a.mode != 4]
        directed = [a for a in goal_attempts if not a.explore and np.isfinite(a.start_distance)]
        landed = [a for a in directed if np.isfinite(a.best_distance)]
        gains = np.array([a.start_distance - a.best_distance for a in landed])

        def mean(values: list[float] | np.ndarray) -> float:
            return float(np.mean(values)) if len(values) else float("nan")

        out: dict = {
            "n_goals": len(goal_attempts),
            "explore_share": mean([a.explore for a in goal_attempts]),
            "gain_mean": mean(gains),
            "gain_positive_share": mean(gains > 0),
            "no_outcome_share": 1.0 - len(landed) / len(directed) if directed else float("nan"),
            "start_distance_mean": mean([a.start_distance for a in landed]),
            "best_distance_mean": mean([a.best_distance for a in landed]),
        }
        if unreachable is not None and landed:
            reach = np.array([unreachable.share(a.goal[None]) == 0.0 for a in landed])
            out["gain_reachable_mean"] = mean(gains[reach])
            out["gain_unreachable_mean"] = mean(gains[~reach])
        true = [a for a in landed if np.isfinite(a.true_best)]
        if true:
            true_gains = np.array([a.true_start - a.true_best for a in true])
            out["true_gain_mean"] = mean(true_gains)
            out["true_gain_positive_share"] = mean(true_gains > 0)
            if unreachable is not None:
                reach = np.array([unreachable.share(a.goal[None]) == 0.0 for a in true])
                out["true_gain_reachable_mean"] = mean(true_gains[reach])
        real, shuffled, corr = interest_against_shuffled(self.learner)
        out.update(interest_real=real, interest_shuffled=shuffled, interest_corr=corr)
        if unreachable is not None:
            shares = []
            for start in range(0, total, frame):
                goals = [a.goal for a in goal_attempts
                         if a.mode == 1 and start < a.movement <= start + frame]
                shares.append(unreachable.share(np.array(goals)) if goals else float("nan"))
            out["mode1_unreachable_share"] = shares
            out["unreachable_area_share"] = unreachable.area_share
        return out


def interest_against_shuffled(learner: GoalBabblingLearner, repeats: int = 20,
                              seed: int = 0) -> tuple[float, float, float]:
    """Mean interest over leaves: real, with each leaf's last-zeta window shuffled (mean of
    ``repeats`` shuffles), and the correlation of the two across leaves. Equal real and
    shuffled means the order of competences (progress) adds nothing over their scatter."""
    tree = learner.tree
    rng = np.random.default_rng(seed)
    real, shuffled = [], []
    for leaf in tree.leaves:
        window = np.asarray(leaf.competences[-tree.zeta:], float)
        if len(window) < 4:
            continue
        real.append(interest(window, tree.zeta, tree.noise_correction))
        shuffled.append(np.mean([interest(rng.permutation(window), tree.zeta,
                                          tree.noise_correction) for _ in range(repeats)]))
    if len(real) < 3:
        return float("nan"), float("nan"), float("nan")
    r, s = np.array(real), np.array(shuffled)
    corr = float(np.corrcoef(r, s)[0, 1]) if r.std() > 0 and s.std() > 0 else float("nan")
    return float(r.mean()), float(s.mean()), corr


@dataclass(frozen=True)
class ReachMap:
    """Cells of a grid over the outcome box that a dense sample of movements never reached."""

    low: np.ndarray
    high: np.ndarray
    reached: np.ndarray  # (cells, cells) bool

    @property
    def area_share(self) -> float:
        """Share of the box's area no movement reaches."""
        return float(1.0 - self.reached.mean())

    def share(self, points: np.ndarray) -> float:
        """Share of the points that fall in never-reached cells."""
        n = np.array(self.reached.shape)
        ij = np.clip(np.floor((points - self.low) / (self.high - self.low) * n).astype(int), 0,
                     n - 1)
        return float(1.0 - self.reached[ij[:, 0], ij[:, 1]].mean())

