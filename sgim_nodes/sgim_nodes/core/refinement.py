"""Refining an action on real movements: three ask/tell optimisers for a ~10-movement budget.

Every cost is a real, noisy movement, so the optimiser proposes (``ask``) and is told what the
movement gave (``tell``). The cost is the distance from the outcome to the goal (a failed
movement costs ``failure_cost``). Chosen by measurement in docs/learners.md
(benchmarks/bench_learners.py prints each optimiser's gain on memory):

- ``LocalLinearSearch``: trust-region Gauss-Newton. Around the best action so far, fit the
  local linear model (local_model.py) on memory, which holds every movement of the attempt,
  and step towards the goal; the radius doubles after a gain and halves after a loss. With 2
  outcome numbers only 2 directions of the 24 matter, which the fit finds from the pairs
  memory already holds around the action: no movement is spent probing directions.
- ``RandomSearch``: a (1+1) evolution strategy with the 1/5th success rule.
- ``NelderMeadSearch``: the ask/tell simplex (nelder_mead.py) seeded from memory.
"""

from __future__ import annotations

import math

import numpy as np

from . import local_model, portable
from .memory import Memory
from .nelder_mead import AskTellNelderMead


class _Search:
    """Keeps the best action and its cost; subclasses propose the next action."""

    def __init__(self, start_action: np.ndarray, start_cost: float) -> None:
        self.best_action = np.asarray(start_action, dtype=float).copy()
        self.best_cost = float(start_cost)

    def ask(self) -> np.ndarray:
        raise NotImplementedError

    def tell(self, action: np.ndarray, cost: float) -> bool:
        """Record a movement's cost; True when it improved on the best."""
        if cost < self.best_cost:
            self.best_action, self.best_cost = np.asarray(action, float).copy(), float(cost)
            return True
        return False


class LocalLinearSearch(_Search):
    def __init__(self, goal: np.ndarray, memory: Memory, start_action: np.ndarray,
                 start_cost: float, radius: float, neighbours: int,
                 rng: np.random.Generator) -> None:
        super().__init__(start_action, start_cost)
        self.last = np.asarray(start_action, float).copy()
        self.goal = np.asarray(goal, dtype=float)
        self.memory = memory
        self.radius = radius
        self.max_radius = 4.0 * radius
        self.neighbours = neighbours
        self.rng = rng

    MODE = "best"

    def ask(self) -> np.ndarray:
        centre = self.best_action if self.MODE == "best" else self.last
        fit = local_model.fit(self.memory, centre, 2.0 * self.radius, self.neighbours)
        if fit is not None:
            action, _ = local_model.step(fit, self.goal, self.radius)
            if portable.norm(action - centre) > 1e-3 * self.radius:
                return action
        # No model yet, or it says stay: probe a random direction at the trust radius.
        direction = self.rng.standard_normal(self.best_action.shape)
        direction *= self.radius / max(portable.norm(direction), 1e-12)
        return np.clip(centre + direction, -1.0, 1.0)

    last = None

    def tell(self, action: np.ndarray, cost: float) -> bool:
        improved = super().tell(action, cost)
        self.last = np.asarray(action, float).copy()
        if self.MODE == "best":
            self.radius = min(self.max_radius, 2.0 * self.radius) if improved else 0.5 * self.radius
        return improved


class ProbeScale:
    """How far to probe so that a probe moves the outcome by a few noise units.

    A probe that moves the outcome by less than the noise teaches nothing (measured: on the
    20-joint arm a 0.45 action step moves the hook 1.8 noise units, and the fitted slopes were
    noise). The learner keeps the median sensitivity (outcome distance per action distance,
    noise removed) of its recent probes, and sizes the next probes to move the outcome by
    ``target`` noise units, within [low, high]. It starts at ``initial``.
    """

    def __init__(self, noise: float, initial: float, low: float, high: float,
                 target: float = 3.0, window: int = 50) -> None:
        self.noise, self.initial, self.low, self.high = noise, initial, low, high
        self.target = target
        self.window = window
        self.samples: list[float] = []

    def radius(self) -> float:
        if not self.samples:
            return self.initial
        sensitivity = float(np.median(self.samples[-self.window:]))
        if sensitivity <= 0.0:
            return self.high
        return float(np.clip(self.target * self.noise / sensitivity, self.low, self.high))

    def observe(self, action_step: float, outcome_step: float) -> None:
        """One probe: |da| and |dy|; the noise's share of |dy| (2 casts) is removed."""
        if action_step <= 0.0:
            return
        signal = max(0.0, outcome_step**2 - 2.0 * self.noise**2) ** 0.5
        self.samples.append(signal / action_step)
        del self.samples[:-self.window]


class SubspaceSearch(_Search):
    """Gauss-Newton on the attempt's own casts, in a random subspace of the action space.

    Memory's pairs around an action come from unrelated directions, with noise as large as the
    outcome changes: a 24-D Jacobian fitted on them is noise (measured: cosine 0.1 to the true
    one on the 20-joint arm). Here the attempt probes m random orthonormal directions U around
    its start action a0 (m = outcome size), at a radius that moves the outcome by a few noise
    units (ProbeScale), so all its casts lie in a0 + span(U), where a linear model
    y ~ b + M c (c = U^T (a - a0)) has only m + 1 coefficients per outcome number: determined
    once the probes are in, and better with every cast (it averages the noise). Each further
    cast is the model's solution for the goal nearest to the best-predicted cast, no farther
    than the trust radius, which grows after a gain and shrinks after a loss.
    """

    def __init__(self, goal: np.ndarray, start_action: np.ndarray, start_outcome,
                 start_cost: float, probe: float, n_probes: int,
                 rng: np.random.Generator, scale: ProbeScale | None = None) -> None:
        super().__init__(start_action, start_cost)
        self.goal = np.asarray(goal, dtype=float)
        self.origin = np.asarray(start_action, dtype=float).copy()
        self.start_outcome = None if start_outcome is None else np.asarray(start_outcome, float)
        n = len(self.origin)
        m = min(n_probes, n)
        q = portable.orthonormal_columns(rng.standard_normal((n, m)))
        self.basis = q  # (n, m), orthonormal columns
        self.coords: list[np.ndarray] = []
        self.outcomes: list[np.ndarray] = []
        if self.start_outcome is not None:
            self.coords.append(np.zeros(m))
            self.outcomes.append(self.start_outcome)
        self.probe = probe
        self.scale = scale
        self.radius = 2.0 * probe
        self._queue = [np.clip(self.origin + probe * q[:, i], -1.0, 1.0) for i in range(m)]
        self.last_cost = start_cost

    def _model(self):
        c = np.array(self.coords)
        y = np.array(self.outcomes)
        design = np.hstack([np.ones((len(c), 1)), c])
        beta = portable.least_squares(design, y)
        return beta[0], beta[1:].T, c  # b, M (outcome, m), coordinates of the casts

    def ask(self) -> np.ndarray:
        if self._queue:
            return self._queue[0].copy()
        m = self.basis.shape[1]
        if len(self.coords) < m + 1:  # probes failed (no outcome): probe around the best
            direction = self.basis[:, len(self.coords) % m]
            return np.clip(self.best_action + self.probe * direction, -1.0, 1.0)
        b, mat, c = self._model()
        predicted = b + portable.matmul(c, mat.T)
        ref = c[int(np.argmin(np.linalg.norm(predicted - self.goal, axis=1)))]
        gap = self.goal - (b + portable.matmul(mat, ref))
        delta = portable.minimum_norm_step(mat, gap)
        norm = portable.norm(delta)
        if norm > self.radius:
            delta *= self.radius / norm
        return np.clip(self.origin + portable.matmul(self.basis, ref + delta), -1.0, 1.0)

    def tell_outcome(self, action: np.ndarray, outcome, cost: float) -> bool:
        probing = bool(self._queue)
        if probing:
            self._queue.pop(0)
        action = np.asarray(action, float)
        if outcome is not None:
            outcome = np.asarray(outcome, float)
            self.coords.append(portable.matmul(self.basis.T, action - self.origin))
            self.outcomes.append(outcome)
            if probing and self.scale is not None and self.start_outcome is not None:
                self.scale.observe(portable.norm(action - self.origin),
                                   portable.norm(outcome - self.start_outcome))
        improved = super().tell(action, cost)
        if not probing:
            self.radius *= 1.5 if cost < self.last_cost else 0.6
        self.last_cost = cost
        return improved


class RandomSearch(_Search):
    """(1+1)-ES: success multiplies sigma by exp(0.8), failure by exp(-0.2) (1/5th rule)."""

    def __init__(self, start_action: np.ndarray, start_cost: float, sigma: float,
                 rng: np.random.Generator) -> None:
        super().__init__(start_action, start_cost)
        self.sigma = sigma
        self.rng = rng

    def ask(self) -> np.ndarray:
        noise = self.rng.normal(0.0, self.sigma, self.best_action.shape)
        return np.clip(self.best_action + noise, -1.0, 1.0)

    def tell(self, action: np.ndarray, cost: float) -> bool:
        improved = super().tell(action, cost)
        self.sigma *= math.exp(0.8) if improved else math.exp(-0.2)
        return improved


class NelderMeadSearch(_Search):
    """Simplex of the start action and the goal's nearest memory pairs (their costs are known:
    no movement spent), padded along the axes when memory is too small."""

    def __init__(self, goal: np.ndarray, memory: Memory, start_action: np.ndarray,
                 start_cost: float, step: float) -> None:
        super().__init__(start_action, start_cost)
        goal = np.asarray(goal, dtype=float)
        n = len(start_action)
        chosen = [int(i) for i in memory.nearest(goal, n)[1]][:n]
        verts = [memory.actions[i].copy() for i in chosen]
        values: list[float | None] = [portable.norm(memory.outcomes[i] - goal)
                                      for i in chosen]
        axis = 0
        while len(verts) < n:
            v = np.asarray(start_action, dtype=float).copy()
            v[axis % n] += step if v[axis % n] + step <= 1 else -step
            verts.append(v)
            values.append(None)
            axis += 1
        self._nm = AskTellNelderMead(np.vstack([start_action, verts]), [start_cost, *values])

    def ask(self) -> np.ndarray:
        return self._nm.ask()

    def tell(self, action: np.ndarray, cost: float) -> bool:
        self._nm.tell(cost)
        return super().tell(action, cost)
