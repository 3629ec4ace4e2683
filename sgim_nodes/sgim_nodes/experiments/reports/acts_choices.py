"""What SGIM-ACTS chose in the active_strategies experiment (issue 33), as page blocks: its
strategies and whom it asked over time, whom it asked about which part of the world at the
end, and the two shares the issue sets goals for, per seed and pooled.

Why from the bags: the graph records each request (HelpRequest: when, whom, about which goal)
and each episode's strategy (the Goal that names it), so these numbers are read from what the
runs did, never from the learner's own bookkeeping.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sgim_nodes.analysis import figures
from sgim_nodes.analysis.report import num, table
from sgim_nodes.analysis.statistics import mean_ci
from sgim_nodes.analysis.strategy_choices import (
    Ask,
    Share,
    asks_by_part,
    asks_from_run,
    by_mode,
    counts_per_window,
    expert_share,
    in_window,
    land_share,
    mean_counts,
    mean_shares,
    part_experts,
    run_strategy_shares,
    teacher_share,
)
from sgim_nodes.analysis.study import RunData
from sgim_nodes.core.experts import FISHING_EXPERTS
from sgim_nodes.core.strategies import MIMICRY

WINDOW = 500
"""Movements per window of the strategies over time (issue 33)."""
LAST = 1000
"""The run's last movements over which its choices are judged (issue 33)."""
EXPERT_SHARE_GOAL = 0.70
"""Issue 33: of the requests about a part one precise expert knows, at least this share goes
to that expert."""
ROUGH = "rough"
ROUGH_SHARE_GOAL = 0.10
"""Issue 33: the rough teacher gets less than this share of the requests."""
FIGURE = "active_strategies_choices.png"


@dataclass(frozen=True)
class Verdict:
    """One of the issue's goals, what the runs gave, and whether that meets it (None: the runs
    give nothing to judge it on)."""

    goal: str
    measured: str
    met: bool | None

    @property
    def word(self) -> str:
        return {True: "met", False: "not met", None: "cannot be judged"}[self.met]


def percent(value: float | None) -> str:
    return "n/a" if value is None else f"{100 * value:.1f} %"


def part_of_outcome() -> Callable[[np.ndarray], str]:
    """The part of the lake (or 'land') an outcome lies in (sim_bridge.lake)."""
    from sim_bridge.lake import Lake

    return Lake().part_of_outcome


def last_asks(run: RunData, last: int) -> list[Ask]:
    """The run's requests in its last ``last`` movements."""
    return in_window(asks_from_run(run), run.total_movements, last)


def page_order(names: set[str]) -> list[str]:
    """Strategies or teachers as the page shows them: autonomous first, then by teacher in
    the experts' order (centre, west, rough), mimicry before emulation."""
    experts = [s.name for s in FISHING_EXPERTS]

    def key(name: str) -> tuple:
        kind, _, teacher = name.partition(":") if ":" in name else ("", "", name)
        known = teacher in experts
        return (name != "autonomous", not known, experts.index(teacher) if known else 0,
                teacher, kind != MIMICRY)

    return sorted(names, key=key)


def per_window(runs: Sequence[RunData], window: int
               ) -> tuple[dict[int, dict[str, float]], dict[int, dict[str, float]]]:
    """Per window of movements: each strategy's share of the episodes chosen, averaged over
    the runs, and the mean requests per run to each teacher, both in the page's order."""
    shares = mean_shares([run_strategy_shares(r, window) for r in runs])
    asked = mean_counts([counts_per_window(((a.movement, a.teacher) for a in asks_from_run(r)),
                                           r.total_movements, window) for r in runs])
    names = page_order({n for v in shares.values() for n in v})
    teachers = page_order({t for v in asked.values() for t in v})
    return ({start: {n: v.get(n, 0.0) for n in names} for start, v in shares.items()},
            {start: {t: v.get(t, 0.0) for t in teachers} for start, v in asked.items()})


def draw(runs: Sequence[RunData], folder: Path, window: int) -> Path:
    """The figure of the strategies and the teachers asked, per window of movements."""
    shares, asked = per_window(runs, window)
    return figures.plot_strategy_shares(shares, asked, window, len(runs), folder / FIGURE)


def strategies_table(runs: Sequence[RunData], window: int) -> str:
    """The figure's numbers: per window, each strategy's mean share of the episodes chosen,
    and the mean requests per run to each teacher."""
    shares, asked = per_window(runs, window)
    names = list(dict.fromkeys(n for v in shares.values() for n in v))
    teachers = list(dict.fromkeys(t for v in asked.values() for t in v))
    rows = [[f"{start}-{start + window}",
             *(percent(shares.get(start, {}).get(n, 0.0)) for n in names),
             *(num(asked.get(start, {}).get(t, 0.0), 1) for t in teachers)]
            for start in sorted(set(shares) | set(asked))]
    return "\n".join(table(["movements", *(f"`{n}`" for n in names),
                            *(f"requests to {t}" for t in teachers)], rows)) + (
        f"\nShares: of the episodes whose (strategy, goal) was chosen in the window, mean over "
        f"the {len(runs)} runs; requests: mean number per run, mimicry and emulation together.")


def regions_table(runs: Sequence[RunData], last: int) -> str:
    """Requests of the last movements by the part of the world the asked goal lies in and the
    teacher asked, pooled over the runs, beside the precise expert of each part."""
    from sim_bridge.lake import PARTS

    part_of = part_of_outcome()
    counts = sum((asks_by_part(last_asks(r, last), part_of) for r in runs),
                 start=asks_by_part([], part_of))
    teachers = [s.name for s in FISHING_EXPERTS]
    teachers += sorted({t for _, t in counts} - set(teachers))
    owners = part_experts(FISHING_EXPERTS)
    rows = []
    for part in (*PARTS, "land"):
        cells = [counts.get((part, t), 0) for t in teachers]
        total = sum(cells)
        owner = owners.get(part)
        share = counts.get((part, owner), 0) / total if owner and total else None
        rows.append([part, owner or "none (no precise expert)", *map(str, cells), str(total),
                     percent(share) if owner else ""])
    return "\n".join(table(["part of the world (asked goal)", "its precise expert", *teachers,
                            "all", "sent to its expert"], rows)) + (
        f"\nRequests made in the last {last} movements of each run, pooled over the "
        f"{len(runs)} runs; the part is where the asked goal lies (sim_bridge.lake).")


def modes_table(runs: Sequence[RunData], last: int) -> str:
    """The requests of the last movements by how their (strategy, goal) was chosen: what the
    learner's interest chose, apart from mode 2's uniform draws of strategy and goal."""
    part_of = part_of_outcome()
    groups: dict[str, list[Ask]] = {}
    for run in runs:
        for name, asks in by_mode(last_asks(run, last)).items():
            groups.setdefault(name, []).extend(asks)
    rows = []
    for name, asks in groups.items():
        land = land_share(asks, part_of)
        expert = expert_share(asks, FISHING_EXPERTS, part_of)
        rough = teacher_share(asks, ROUGH)
        rows.append([name, str(len(asks)), percent(land.value),
                     f"{percent(expert.value)} ({expert.hits} of {expert.total})",
                     f"{percent(rough.value)} ({rough.hits} of {rough.total})"])
    unmatched = sum(a.mode == 0 for a in groups.get("all", []))
    return "\n".join(table(["requests chosen", f"requests (last {last} movements)",
                            "about a goal on land", "expert share", "rough's share"], rows)) + (
        f"\nPooled over the {len(runs)} runs. Mode 2 draws the strategy uniformly and the goal "
        "uniformly in the whole outcome box (strategy_choice.py); modes 1 and 3 draw the "
        "(strategy, region) pair by its interest divided by its cost."
        + (f" {unmatched} requests matched no recorded choice." if unmatched else ""))


@dataclass(frozen=True)
class ChoiceShares:
    """Per run (in seed order) and pooled: the expert share and rough's share."""

    seeds: list[int]
    expert: list[Share]
    rough: list[Share]

    @staticmethod
    def pooled(shares: list[Share]) -> Share:
        return Share(sum(s.hits for s in shares), sum(s.total for s in shares))


def choice_shares(runs: Sequence[RunData], last: int) -> ChoiceShares:
    part_of = part_of_outcome()
    asks = [last_asks(r, last) for r in runs]
    return ChoiceShares([r.seed for r in runs],
                        [expert_share(a, FISHING_EXPERTS, part_of) for a in asks],
                        [teacher_share(a, ROUGH) for a in asks])


def _judged(what: str, shares: list[Share], goal: float, at_least: bool) -> Verdict:
    pooled = ChoiceShares.pooled(shares)
    values = [s.value for s in shares if s.value is not None]
    ci = mean_ci(values)
    meets = [v >= goal if at_least else v < goal for v in values]
    measured = (f"pooled {percent(pooled.value)} ({pooled.hits} of {pooled.total}); mean over "
                f"runs {percent(ci.mean)}"
                + (f" [{percent(ci.low)}, {percent(ci.high)}]" if ci.low is not None else "")
                + f"; {sum(meets)} of {len(values)} runs meet it")
    met = None if pooled.value is None else (
        pooled.value >= goal if at_least else pooled.value < goal)
    said = f"at least {percent(goal)}" if at_least else f"below {percent(goal)}"
    return Verdict(f"{what} {said}", measured, met)


def verdicts(shares: ChoiceShares, last: int) -> list[Verdict]:
    """The issue's two goals on SGIM-ACTS's choices, judged on the pooled shares."""
    return [_judged(f"the expert share (of the requests of the last {last} movements about a "
                    "part one precise expert knows, the share sent to that expert)",
                    shares.expert, EXPERT_SHARE_GOAL, True),
            _judged(f"rough's share of the requests of the last {last} movements",
                    shares.rough, ROUGH_SHARE_GOAL, False)]


def shares_table(shares: ChoiceShares, last: int) -> str:
    """Per seed and pooled, the two shares, then the verdicts."""
    def cells(expert: Share, rough: Share) -> list[str]:
        return [str(rough.total), str(expert.total), str(expert.hits), percent(expert.value),
                str(rough.hits), percent(rough.value)]

    rows = [[str(seed), *cells(e, r)]
            for seed, e, r in zip(shares.seeds, shares.expert, shares.rough, strict=True)]
    rows.append(["**pooled**", *cells(ChoiceShares.pooled(shares.expert),
                                      ChoiceShares.pooled(shares.rough))])
    out = table(["seed", f"requests (last {last} movements)",
                 "about a part one precise expert knows", "sent to that expert",
                 f"expert share (goal: at least {percent(EXPERT_SHARE_GOAL)})",
                 "sent to rough", f"rough's share (goal: below {percent(ROUGH_SHARE_GOAL)})"],
                rows)
    out += [f"- Goal: {v.goal}. The runs: {v.measured}. **{v.word.capitalize()}**, judged "
            "on the pooled share." for v in verdicts(shares, last)]
    return "\n".join(out)
