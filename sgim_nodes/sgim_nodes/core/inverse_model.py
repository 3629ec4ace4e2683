"""The local inverse model: from a goal outcome to ONE action, never an average of several.

The paper ranks the l_max stored outcomes nearest to the goal by reliability = distance + alpha
* variance, where the variance is that of the actions that produced the candidate's k_max
outcome neighbours: a candidate whose neighbourhood was produced by similar actions is a
consistent place to act from. The paper then interpolated the neighbours' actions; in a
redundant action space that average lands away from all of them (issue 10: it made about 60 %
of the final error), so every method here returns one stored action, possibly moved by a
linear model fitted in that action's own neighbourhood:

- ``nearest``: the action of the stored outcome nearest to the goal;
- ``reliable``: the action of the most reliable candidate (the paper's rank, no average);
- ``local-linear``: among the l_max candidates, the action whose outcome, as predicted by a
  linear model fitted on the pairs around it in action space (local_model.py), lies closest
  to the goal: the prediction averages the noise of every cast near the action, where a
  single stored outcome carries it whole. A candidate with no close pairs, or whose fit
  averages fewer than ``rank_min_casts`` casts, is ranked by its own stored outcome, so on a
  memory with no clusters this is the nearest neighbour. The chosen action is then moved by
  one step of that model towards the goal, no farther than ``local_step`` (a quarter of the
  fitted radius by default: measured, docs/learners.md) nor ``step_support`` times the fit's
  spread of actions along the step (no extrapolation past the casts the fit stands on), and
  only when the fit averages at least ``min_casts`` casts: a fit on a handful of casts in 24
  dimensions follows their noise, and its step lost to the nearest neighbour on sparse
  fishing memories; and, given the world's noise (``noise_rms``), only when the gain the
  step predicts (how much closer to the goal than the unmoved action) exceeds the fit's
  misfit, its held-out error beyond that noise: a predicted gain smaller than what the model
  gets wrong on casts it did not see is no evidence. On the fishing world's non-smooth
  actions the step then stays out where it lost (docs/learners.md, section 1); on the smooth
  arms, where the fit predicts to within the noise, it is kept.

docs/learners.md compares the three on the same memories (benchmarks/bench_inverse.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import local_model, portable
from .fit_cache import FitCache
from .memory import Memory


def action_variance(actions: np.ndarray) -> float:
    """Mean per-dimension variance of a set of actions (mean squared distance to their mean,
    divided by the action dimension) so that the scale does not grow with the dimension."""
    actions = np.asarray(actions, dtype=float)
    centred = actions - actions.mean(axis=0)
    return float((centred**2).sum(axis=1).mean() / actions.shape[1])


def reliability(distance: float, variance: float, alpha: float) -> float:
    """Paper: distance + alpha * variance (lower = more reliable)."""
    return float(distance + alpha * variance)


@dataclass(frozen=True)
class InverseEstimate:
    action: np.ndarray
    candidate_index: int  # memory index of the stored pair the action comes from
    reliability: float
    predicted_outcome: np.ndarray  # where the model expects the action to land


class InverseModel:
    """Reads the memory only; never learns on its own."""

    def __init__(self, memory: Memory, method: str = "reliable", l_max: int = 10,
                 k_max: int = 5, alpha: float = 0.5, local_radius: float = 1.0,
                 local_neighbours: int = 60, local_step: float = 0.25,
                 min_casts: float = 0.0, noise_rms: float | None = None,
                 rank_min_casts: float = 0.0, step_support: float = 0.0) -> None:
        if method not in ("nearest", "reliable", "local-linear"):
            raise ValueError(f"unknown inverse model {method!r}")
        self.memory = memory
        self.method = method
        self.l_max = l_max
        self.k_max = k_max
        self.alpha = alpha
        self.local_radius = local_radius
        self.local_neighbours = local_neighbours
        self.local_step = local_step
        self.min_casts = min_casts
        self.noise_rms = noise_rms
        self.rank_min_casts = rank_min_casts
        self.step_support = step_support
        self.fits = FitCache(memory, local_radius, local_neighbours)

    def most_reliable(self, goal: np.ndarray) -> tuple[int, float]:
        """Memory index and score of the most reliable of the l_max candidates."""
        mem = self.memory
        cand_d, cand_i = mem.nearest(goal, self.l_max)
        _, neigh_i = mem.nearest(mem.outcomes[cand_i], self.k_max)
        scores = [reliability(cand_d[j], action_variance(mem.actions[neigh_i[j]]), self.alpha)
                  for j in range(len(cand_i))]
        best = int(np.argmin(scores))
        return int(cand_i[best]), float(scores[best])

    def estimate(self, goal: np.ndarray) -> InverseEstimate | None:
        """None when the memory is empty."""
        mem = self.memory
        if len(mem) == 0:
            return None
        goal = np.asarray(goal, dtype=float)
        if self.method == "nearest":
            d, i = mem.nearest(goal, 1)
            index, score = int(i[0]), float(d[0])
            outcome = mem.outcomes[index].copy()
        elif self.method == "reliable":
            index, score = self.most_reliable(goal)
            outcome = mem.outcomes[index].copy()
        else:
            index, score, outcome, fit = self.best_predicted(goal)
            if fit is not None and fit.n_effective >= self.min_casts:
                action, predicted = local_model.step(fit, goal, self.local_step,
                                                     self.step_support)
                # A flat or undetermined fit predicts (almost) no change: then stay put.
                if (portable.norm(predicted - fit.outcome) > 0.05 * score
                        and self._step_is_evidenced(fit, score, goal, predicted)):
                    return InverseEstimate(action, index, score, predicted)
        return InverseEstimate(mem.actions[index].copy(), index, score, outcome)

    def _step_is_evidenced(self, fit: local_model.LocalFit, unmoved_distance: float,
                           goal: np.ndarray, predicted: np.ndarray) -> bool:
        """Does the step's predicted gain exceed what the fit gets wrong beyond noise?
        ``unmoved_distance``: the fit's prediction at its centre to the goal (the rank score)."""
        if self.noise_rms is None:
            return True
        gain = unmoved_distance - portable.norm(predicted - goal)
        return gain > fit.misfit(self.noise_rms)

    def best_predicted(self, goal: np.ndarray
                       ) -> tuple[int, float, np.ndarray, local_model.LocalFit | None]:
        """The candidate whose locally predicted outcome is nearest to the goal: memory index,
        that distance, the predicted outcome and the fit (None: too few pairs around it, or a
        fit averaging fewer than ``rank_min_casts`` casts; then the stored outcome ranks)."""
        mem = self.memory
        _, cand_i = mem.nearest(goal, self.l_max)
        best: tuple[int, float, np.ndarray, local_model.LocalFit | None] | None = None
        for i in cand_i:
            fit = self.fits.get(i)
            if fit is not None and fit.n_effective < self.rank_min_casts:
                fit = None  # too few casts to predict better than the stored outcome
            predicted = mem.outcomes[i] if fit is None else fit.outcome
            d = portable.norm(predicted - goal)
            if best is None or d < best[1]:
                best = (int(i), d, np.array(predicted, dtype=float), fit)
        assert best is not None
        return best

    def __call__(self, goal: np.ndarray) -> np.ndarray | None:
        est = self.estimate(goal)
        return None if est is None else est.action
