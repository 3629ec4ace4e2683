"""What an SGIM-ACTS run chose: whom it asked, where, and how that changed (issue 33).

The issue's two questions about the learner's choices, answered from its requests:

- does it ask each expert where that expert knows? ``expert_share``: of the requests about
  goals in a part of the world that one precise expert knows, the share sent to that expert;
- does it stop asking ``rough`` once it does better alone? ``teacher_share``: rough's share of
  all requests.

Both over the run's last ``window`` movements (the issue: 1000), and ``strategy_shares`` gives
the choice of strategy per window of movements, for the curves. They read ``Ask`` values:
``asks_from_runner`` makes them from the runner's records (core/acts_runner.py) and
``asks_from_run`` from a graph run's HelpRequest records (analysis/study.py keeps them), which
name the teacher and the goal the same way; ``strategy_shares`` and ``run_strategy_shares``
read the episodes' strategies from either.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sgim_nodes.core.experts import ExpertSpec
from sgim_nodes.core.strategies import EMULATION, MIMICRY
from sgim_nodes.core.teaching import GOAL_ONLY

if TYPE_CHECKING:
    from sgim_nodes.analysis.study import RunData


@dataclass(frozen=True)
class Ask:
    """One request: when (the learner's movement count), whom, about which goal, and the goal
    mode that chose its (strategy, goal) (1 and 3: by interest, 2: at random; 0: unknown)."""

    movement: int
    teacher: str
    goal: np.ndarray
    mode: int = 0


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


def asks_from_run(run: RunData) -> list[Ask]:
    """The requests of a graph run: its HelpRequest records (count when asked, teacher, goal);
    none for a run of another learner or a bag recorded without them. Each takes its mode
    from the episode's choice: the k-th request of a strategy at a count is the k-th choice of
    that strategy at that count (a request asks at the count its goal was chosen)."""
    modes: dict[tuple[int, str], list[int]] = {}
    for m, strategy, mode in zip(run.choice_index, run.choice_strategy, run.choice_mode,
                                 strict=True):
        modes.setdefault((int(m), str(strategy)), []).append(int(mode))
    asks = []
    for m, t, content, g in zip(run.ask_index, run.ask_teacher, run.ask_content, run.ask_goal,
                                strict=True):
        kind = EMULATION if content == GOAL_ONLY else MIMICRY
        found = modes.get((int(m), f"{kind}:{t}"))
        asks.append(Ask(int(m), str(t), np.asarray(g, dtype=float),
                        found.pop(0) if found else 0))
    return asks


def by_mode(asks: Iterable[Ask]) -> dict[str, list[Ask]]:
    """The asks whose (strategy, goal) was chosen by interest (modes 1 and 3), at random
    (mode 2), and all of them."""
    asks = list(asks)
    return {"by interest (modes 1 and 3)": [a for a in asks if a.mode in (1, 3)],
            "at random (mode 2)": [a for a in asks if a.mode == 2],
            "all": asks}


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


def land_share(asks: Iterable[Ask], part_of: Callable[[np.ndarray], str]) -> Share:
    """The share of the asks about a goal on land, where no part of the lake is."""
    asks = list(asks)
    return Share(sum(part_of(a.goal) == "land" for a in asks), len(asks))


Window = tuple[int, dict[str, float]]
"""A window of movements (its first movement) and the share of each name in it."""


def counts_per_window(events: Iterable[tuple[int, str]], movements: int, window: int
                      ) -> list[tuple[int, Counter]]:
    """(movement, name) events counted per window of ``window`` movements (its first
    movement), windows without an event left out."""
    by_window: dict[int, Counter] = {}
    for movement, name in events:
        by_window.setdefault(int(movement) // window * window, Counter())[str(name)] += 1
    return [(start, c) for start, c in sorted(by_window.items()) if start < movements]


def _shares(counted: list[tuple[int, Counter]]) -> list[Window]:
    return [(start, {s: n / sum(c.values()) for s, n in sorted(c.items())})
            for start, c in counted]


def strategy_shares(records: Iterable[Mapping], movements: int, window: int) -> list[Window]:
    """Per window of movements (its first movement), the share of each strategy among the
    episodes chosen in it (runner "strategy_choice" records)."""
    return _shares(counts_per_window(((r["movement"], r["strategy"]) for r in records
                                      if r.get("type") == "strategy_choice"), movements, window))


def run_strategy_shares(run: RunData, window: int) -> list[Window]:
    """strategy_shares of a graph run: its episodes' strategies, each at the count when its
    (strategy, goal) was chosen (the Goals that name a strategy)."""
    return _shares(counts_per_window(zip(run.choice_index, run.choice_strategy, strict=True),
                                     run.total_movements, window))


def mean_shares(per_run: Sequence[list[Window]]) -> dict[int, dict[str, float]]:
    """Per window, each name's share averaged over the runs that chose anything in it (a run
    that never chose a name there counts 0 for it): every run weighs the same, however many
    episodes it had."""
    found: dict[int, list[dict[str, float]]] = {}
    for windows in per_run:
        for start, shares in windows:
            found.setdefault(start, []).append(shares)
    names = sorted({n for runs in found.values() for shares in runs for n in shares})
    return {start: {n: float(np.mean([s.get(n, 0.0) for s in runs])) for n in names}
            for start, runs in sorted(found.items())}


def mean_counts(per_run: Sequence[list[tuple[int, Counter]]]) -> dict[int, dict[str, float]]:
    """Per window, each name's count averaged over all the runs (0 where a run had none)."""
    names = sorted({n for windows in per_run for _, c in windows for n in c})
    starts = sorted({start for windows in per_run for start, _ in windows})
    totals = {start: Counter() for start in starts}
    for windows in per_run:
        for start, c in windows:
            totals[start].update(c)
    return {start: {n: totals[start][n] / len(per_run) for n in names} for start in starts}


def asks_by_part(asks: Iterable[Ask], part_of: Callable[[np.ndarray], str]) -> Counter:
    """(part of the world the asked goal lies in, teacher asked) -> requests."""
    return Counter((part_of(a.goal), a.teacher) for a in asks)
