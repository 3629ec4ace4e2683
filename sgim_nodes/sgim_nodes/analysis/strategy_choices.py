"""What an SGIM-ACTS run chose: whom it asked, where, and how that changed (issue 33).

The issue's two questions about the learner's choices, answered from its requests:

- does it ask each expert where that expert knows? ``expert_share``: of the requests about
  goals in a part of the world that one precise expert knows, the share sent to that expert;
- does it stop asking ``rough`` once it does better alone? ``teacher_share``: rough's share of
  all requests.

Both over the run's last ``window`` movements (the issue: 1000), and ``strategy_shares`` gives
the choice of strategy per window of movements, for the curves. They read ``Ask`` values:
``asks_from_runner`` makes them from the runner's records (core/acts_runner.py); the graph's
HelpRequest records name the teacher and the goal the same way.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sgim_nodes.core.experts import ExpertSpec


@dataclass(frozen=True)
class Ask:
    """One request: when (the learner's movement count), whom, about which goal."""

    movement: int
    teacher: str
    goal: np.ndarray


@dataclass(frozen=True)
class Share:
    """``hits`` of ``total`` requests; ``value`` is None when there were none."""

    hits: int
    total: int

    @property
    def value(self) -> float | None:
        return self.hits / self.total if self.total else None


def asks_from_runner(records: Iterable[Mapping]) -> list[Ask]:
    """The requests of a runner's records (type "request")."""
    return [Ask(int(r["movement"]), str(r["teacher"]), np.asarray(r["goal"], dtype=float))
            for r in records if r.get("type") == "request"]


def part_experts(specs: Sequence[ExpertSpec]) -> dict[str, str]:
    """Part of the world -> the one precise expert that knows it (specs naming parts, with
    precision 0); a part two precise experts know has no single expert and is left out."""
    owners: dict[str, list[str]] = {}
    for spec in specs:
        kind, _, parts = spec.part.partition(":")
        if kind == "parts" and spec.precision == 0.0:
            for part in parts.split("+"):
                owners.setdefault(part, []).append(spec.name)
    return {part: names[0] for part, names in owners.items() if len(names) == 1}


def in_window(asks: Iterable[Ask], movements: int, window: int) -> list[Ask]:
    """The asks made in the run's last ``window`` movements (all, when window is 0)."""
    start = max(0, movements - window) if window else 0
    return [a for a in asks if a.movement >= start]


def expert_share(asks: Iterable[Ask], specs: Sequence[ExpertSpec],
                 part_of: Callable[[np.ndarray], str]) -> Share:
    """Of the asks about a goal in a part one precise expert knows, those sent to it."""
    experts = part_experts(specs)
    owned = [(a, experts[p]) for a in asks if (p := part_of(a.goal)) in experts]
    return Share(sum(a.teacher == owner for a, owner in owned), len(owned))


def teacher_share(asks: Iterable[Ask], teacher: str) -> Share:
    """The share of the asks sent to ``teacher``."""
    asks = list(asks)
    return Share(sum(a.teacher == teacher for a in asks), len(asks))


def strategy_shares(records: Iterable[Mapping], movements: int, window: int
                    ) -> list[tuple[int, dict[str, float]]]:
    """Per window of movements (its first movement), the share of each strategy among the
    episodes chosen in it (runner "strategy_choice" records)."""
    by_window: dict[int, Counter] = {}
    for r in records:
        if r.get("type") == "strategy_choice":
            start = int(r["movement"]) // window * window
            by_window.setdefault(start, Counter())[str(r["strategy"])] += 1
    return [(start, {s: n / sum(c.values()) for s, n in sorted(c.items())})
            for start, c in sorted(by_window.items()) if start < movements]
