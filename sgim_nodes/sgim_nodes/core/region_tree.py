"""The SAGG-RIAC region tree: regions of the outcome space with an interest per region.

Interest (paper eq. 2) is the absolute change of competence over the last zeta goals of a
region: |sum(older half) - sum(newer half)| / zeta.  Regions split once they hold more than
``max_goals`` goals, at the cut maximising the difference of interest of the two children,
so that the tree separates where the learner progresses from where it does not.

Split quality: the cut maximising |interest(left) - interest(right)| alone (``gap``) favours
lopsided cuts, since a child of a few goals has the most extreme window; Baranes & Oudeyer
(2013, after R-IAC, 2009) weigh the gap by the children's sizes, Qual = card(left) *
card(right) * sqrt(|interest(left) - interest(right)|) (``balanced``), so a cut must separate
two well-populated parts of the region.

Noise: with 10 goals per half, the difference of two half-sums is mostly sampling noise when
competences scatter (measured: shuffling a leaf's window gave as much interest as its real
order, docs/learners.md). ``noise_correction`` c removes from the difference of the halves'
means c standard errors of that difference, so a window whose halves differ by no more than
their own scatter has no interest; c = 0 is the paper's formula.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def interest(competences: np.ndarray | list[float], zeta: int,
             noise_correction: float = 0.0) -> float:
    """Eq. 2 on the last zeta competences (chronological order, newest last).

    With fewer than zeta values we use the largest even number m of the newest ones, still
    divided by zeta: two equal halves keep a constant competence at zero interest, and the
    1/zeta factor damps interest estimated from few goals.  With ``noise_correction`` c > 0,
    |sum(older) - sum(newer)| becomes h * max(0, |mean(older) - mean(newer)| - c * se), se the
    standard error of the difference of the two half means of h values each.
    """
    c = np.asarray(competences, dtype=float)
    m = min(len(c), zeta)
    m -= m % 2
    if m == 0:
        return 0.0
    window = c[len(c) - m:]
    h = m // 2
    older, newer = window[:h], window[h:]
    gap = abs(older.mean() - newer.mean())
    if noise_correction > 0.0 and h >= 2:
        se = np.sqrt((older.var(ddof=1) + newer.var(ddof=1)) / h)
        gap = max(0.0, gap - noise_correction * se)
    return float(h * gap / zeta)


@dataclass(eq=False)  # identity comparison: regions are tree nodes
class Region:
    """A box [low, high) of the outcome space (closed on the upper bound of the space)."""

    low: np.ndarray
    high: np.ndarray
    goals: list[np.ndarray] = field(default_factory=list)
    competences: list[float] = field(default_factory=list)
    children: tuple[Region, Region] | None = None
    split_dim: int = -1
    split_value: float = 0.0
    retry_at: int = 0  # after a failed split, wait until the region holds this many goals

    @property
    def is_leaf(self) -> bool:
        return self.children is None

    @property
    def volume(self) -> float:
        return float(np.prod(self.high - self.low))

    def interest(self, zeta: int, noise_correction: float = 0.0) -> float:
        return interest(self.competences, zeta, noise_correction)

    def contains(self, point: np.ndarray) -> bool:
        return bool(np.all(point >= self.low) and np.all(point <= self.high))


SPLIT_QUALITIES = ("gap", "balanced")


def split_quality(kind: str, gap: float, n_left: int, n_right: int) -> float:
    """``gap``: the interest gap; ``balanced``: card(left) * card(right) * sqrt(gap)."""
    if kind == "balanced":
        return float(n_left * n_right * np.sqrt(gap))
    return float(gap)


@dataclass(frozen=True)
class SplitChoice:
    dim: int
    value: float
    score: float  # split_quality of the cut
    n_left: int
    n_right: int


def best_split(goals: np.ndarray, competences: np.ndarray, low: np.ndarray, high: np.ndarray,
               zeta: int, min_per_child: int, min_width: float,
               noise_correction: float = 0.0, quality: str = "gap") -> SplitChoice | None:
    """The cut maximising split_quality(quality, ...) (left: coordinate < value); ``gap`` is
    |interest(left) - interest(right)|.

    Candidates: every midpoint between consecutive distinct sorted coordinates of the goals,
    on every dimension at least ``min_width`` wide, leaving >= min_per_child goals per side.
    Ties (e.g. all competences equal, every score 0) go to the most balanced cut, then the
    lowest dimension and value, so the choice is deterministic.  None if no cut is valid.
    """
    goals = np.asarray(goals, dtype=float)
    competences = np.asarray(competences, dtype=float)
    n = len(goals)
    best: SplitChoice | None = None
    best_key: tuple[float, int] | None = None
    for dim in range(goals.shape[1]):
        if high[dim] - low[dim] < min_width:
            continue
        coords = np.unique(goals[:, dim])
        for value in 0.5 * (coords[:-1] + coords[1:]):
            left = goals[:, dim] < value
            n_left = int(left.sum())
            if n_left < min_per_child or n - n_left < min_per_child:
                continue
            gap = abs(interest(competences[left], zeta, noise_correction)
                      - interest(competences[~left], zeta, noise_correction))
            score = split_quality(quality, gap, n_left, n - n_left)
            key = (round(score, 12), -abs(2 * n_left - n))
            if best_key is None or key > best_key:
                best_key = key
                best = SplitChoice(dim, float(value), float(score), n_left, n - n_left)
    return best


class RegionTree:
    """Leaves partition the outcome space; each attempted goal and its competence go to the
    leaf containing the goal."""

    def __init__(self, low: np.ndarray, high: np.ndarray, max_goals: int, zeta: int,
                 min_per_child: int = 5, min_width: float = 0.05,
                 noise_correction: float = 0.0, split: str = "gap") -> None:
        if split not in SPLIT_QUALITIES:
            raise ValueError(f"split must be one of {SPLIT_QUALITIES}, got {split!r}")
        self.root = Region(np.array(low, dtype=float), np.array(high, dtype=float))
        self.max_goals = max_goals
        self.zeta = zeta
        self.min_per_child = min_per_child
        self.min_width = min_width
        self.noise_correction = noise_correction
        self.split = split
        self._leaves: list[Region] = [self.root]

    @property
    def leaves(self) -> list[Region]:
        return list(self._leaves)

    def leaf_for(self, point: np.ndarray) -> Region:
        node = self.root
        while node.children is not None:
            left = point[node.split_dim] < node.split_value
            node = node.children[0] if left else node.children[1]
        return node

    def add(self, goal: np.ndarray, competence: float) -> Region:
        """Record one attempted goal; split its leaf if it now holds more than max_goals."""
        goal = np.clip(np.asarray(goal, dtype=float), self.root.low, self.root.high)
        leaf = self.leaf_for(goal)
        leaf.goals.append(goal)
        leaf.competences.append(float(competence))
        if len(leaf.goals) > max(self.max_goals, leaf.retry_at - 1):
            self._split(leaf)
        return leaf

    def _split(self, leaf: Region) -> None:
        choice = best_split(np.array(leaf.goals), np.array(leaf.competences), leaf.low,
                            leaf.high, self.zeta, self.min_per_child, self.min_width,
                            self.noise_correction, self.split)
        if choice is None:
            # No valid cut (e.g. every goal on one point): retry once the region grew by half,
            # so a stuck region does not cost a full search on every goal.
            leaf.retry_at = len(leaf.goals) + max(1, len(leaf.goals) // 2)
            return
        left_high = leaf.high.copy()
        left_high[choice.dim] = choice.value
        right_low = leaf.low.copy()
        right_low[choice.dim] = choice.value
        left, right = Region(leaf.low.copy(), left_high), Region(right_low, leaf.high.copy())
        for g, c in zip(leaf.goals, leaf.competences, strict=True):
            child = left if g[choice.dim] < choice.value else right
            child.goals.append(g)
            child.competences.append(c)
        leaf.children = (left, right)
        leaf.split_dim, leaf.split_value = choice.dim, choice.value
        leaf.goals, leaf.competences = [], []
        i = self._leaves.index(leaf)
        self._leaves[i:i + 1] = [left, right]

    def interests(self) -> np.ndarray:
        return np.array([leaf.interest(self.zeta, self.noise_correction)
                         for leaf in self._leaves])
