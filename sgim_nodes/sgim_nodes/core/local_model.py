"""A linear model of the world fitted inside ONE consistent action neighbourhood.

In a redundant action space (24 numbers for 2 outcome numbers) outcomes near a goal come from
many unrelated actions; a model that averages them lands somewhere else (issue 10 measured
60 % of the final error coming from that). A linear model is only meaningful around one
action: we fit y ~ b + J (a - a_c) on the stored pairs within ``radius`` of a_c IN ACTION SPACE,
with Gaussian weights of standard deviation radius / 2 and a small ridge on J.

What it is good for, measured in docs/learners.md: ``b``, the outcome the model predicts AT a_c,
averages the noise of every cast around a_c (a stored outcome carries the world's full noise),
so the inverse model can rank candidate actions by where they really land rather than by where
they once landed by luck. The slope J is poorly determined from memory (the pairs around an
action lie along a few directions, with noise as large as the outcome changes: its cosine to
the true Jacobian was 0.1 on the 20-joint arm); the ridge keeps it small off those directions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import portable
from .memory import Memory

RIDGE = 1e-2
"""Ridge on J relative to the mean weighted squared action offset: J stays defined (and small)
in the directions the neighbourhood does not span."""
MIN_PAIRS = 3
"""Fewer pairs than this within the radius: no fit (the candidate's own outcome is used)."""


@dataclass(frozen=True)
class LocalFit:
    centre: np.ndarray  # the action the model is linearised at
    outcome: np.ndarray  # b: the predicted outcome at the centre (a noise-averaged estimate)
    jacobian: np.ndarray  # J, (outcome_dim, action_dim)
    n_effective: float  # (sum w)^2 / sum w^2: how many casts the estimate averages
    residual: float  # weighted rms residual (noise plus curvature), in outcome units
    # What the held-out error is computed from, only when asked (most fits never are):
    design: np.ndarray | None = field(repr=False, compare=False, default=None)  # sqrt(w)[1, x]
    ridge: float = field(repr=False, compare=False, default=0.0)
    residuals: np.ndarray | None = field(repr=False, compare=False, default=None)
    weights: np.ndarray | None = field(repr=False, compare=False, default=None)

    @cached_property
    def held_out(self) -> float:
        """Weighted rms leave-one-out error, in outcome units: residuals e_i / (1 - h_ii), h
        the weighted hat matrix, without refitting; the ridge rows are a prior, never left
        out."""
        d, w = self.design, self.weights
        gram = portable.matmul(d.T, d) + np.diag(np.r_[0.0, np.full(d.shape[1] - 1,
                                                                     self.ridge)])
        hat = (d * portable.solve_spd(gram, d.T).T).sum(axis=1)
        loo = self.residuals / np.maximum(1.0 - hat, 1e-9)[:, None]
        return float(np.sqrt((w * (loo**2).sum(1)).sum() / w.sum()))

    def spread_along(self, direction: np.ndarray) -> float:
        """Weighted rms offset of the fit's actions from its centre along ``direction`` (a unit
        vector): how far out, that way, the fit has casts to stand on."""
        offsets = self.design[:, 1:]  # sqrt(w) * (a_i - a_c)
        return portable.norm(portable.matmul(offsets, direction)) / math.sqrt(
            self.weights.sum())

    def misfit(self, noise_rms: float) -> float:
        """The held-out error beyond the world's noise (rms distance of one cast from its
        mean): what the model itself gets wrong, 0 when it predicts as well as noise allows."""
        return float(np.sqrt(max(self.held_out**2 - noise_rms**2, 0.0)))


def fit(memory: Memory, centre: np.ndarray, radius: float, max_pairs: int) -> LocalFit | None:
    """The local linear model around ``centre`` from the (at most ``max_pairs``) stored actions
    within ``radius`` of it; None when fewer than MIN_PAIRS are that close."""
    dist, idx = memory.nearest_actions(centre, max_pairs)
    keep = dist <= radius
    dist, idx = dist[keep], idx[keep]
    if len(idx) < MIN_PAIRS:
        return None
    centre = np.asarray(centre, dtype=float)
    x = memory.actions[idx] - centre
    y = memory.outcomes[idx]
    w = portable.exp(-0.5 * (dist / (0.5 * radius)) ** 2)
    sw = np.sqrt(w)[:, None]
    n_act = x.shape[1]
    design = np.hstack([np.ones((len(idx), 1)), x]) * sw
    spread = float((w[:, None] * x**2).sum() / w.sum())
    lam = RIDGE * max(spread, 1e-12)
    # The ridge-regularised normal equations: the ridge keeps the Gram matrix well conditioned
    # (the intercept column is never zero-weighted), and a solve is a fraction of lstsq's SVD.
    gram = portable.matmul(design.T, design)
    gram[np.arange(1, n_act + 1), np.arange(1, n_act + 1)] += lam
    beta = portable.solve_spd(gram, portable.matmul(design.T, y * sw))
    b, jac = beta[0], beta[1:].T
    resid = y - (b + portable.matmul(x, jac.T))
    rms = float(np.sqrt((w * (resid**2).sum(1)).sum() / w.sum()))
    total = float(w.sum())
    return LocalFit(centre, b, jac, total * total / float((w * w).sum()), rms, design, lam,
                    resid, w)


def step(model: LocalFit, goal: np.ndarray, radius: float,
         support: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The action the model says reaches ``goal``, no farther than ``radius`` from its centre
    and, when ``support`` > 0, no farther than ``support`` times the fit's spread of actions
    along the step's direction (a linear model is evidence only where its casts are: past
    them it extrapolates), clipped to [-1, 1]; with the outcome the model predicts for it."""
    jac = model.jacobian
    gap = np.asarray(goal, dtype=float) - model.outcome
    delta = portable.minimum_norm_step(jac, gap)
    norm = portable.norm(delta)
    limit = radius if radius > 0.0 else np.inf
    if support > 0.0 and norm > 0.0:
        limit = min(limit, support * model.spread_along(delta / norm))
    if norm > limit:
        delta *= limit / norm
    action = np.clip(model.centre + delta, -1.0, 1.0)
    return action, model.outcome + portable.matmul(jac, action - model.centre)
