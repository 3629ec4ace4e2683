"""SGIM-ACTS's four arms in the active_strategies experiment, and the predictions pinned for
the next choice (docs/active_strategies.md, "The next choice"): each arm's error, requests,
demonstrations and shares, the shares over time, and P1-P4 judged as written.

An arm is named by its two switches (LearnerConfig.strategy_choice_order and
strategy_value): today's choice (pair, interest), (A) region first, (B) gain, and (A)+(B).
P2 needs the values that made each choice, which no bag records: they come from replaying the
(A)+(B) runs (experiments/acts_values.py), checked movement for movement against the runs and
kept beside the shipped run tables.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import yaml

from sgim_nodes.analysis import figures, strategy_choices
from sgim_nodes.analysis.report import StudyNumbers, num, pval, table
from sgim_nodes.analysis.statistics import PairTest, compare_groups
from sgim_nodes.analysis.strategy_choices import (
    Ask,
    Share,
    asks_from_run,
    expert_share,
    teacher_share,
)
from sgim_nodes.analysis.study import RunData, Study
from sgim_nodes.core.experts import FISHING_EXPERTS
from sgim_nodes.core.learner_registry import SGIM_ACTS, SGIM_D
from sgim_nodes.experiments import acts_values
from sgim_nodes.experiments.makers import say
from sgim_nodes.experiments.reports import acts_choices
from sgim_nodes.experiments.reports.acts_choices import Verdict, percent
from sgim_nodes.sweep.sweep_file import RunSpec

ARMS = {("pair", "interest"): "today's choice", ("region-first", "interest"): "(A) region first",
        ("pair", "gain"): "(B) gain", ("region-first", "gain"): "(A)+(B)"}
BOTH = ARMS[("region-first", "gain")]
FIGURE = "active_strategies_arms.png"
P1_RUNS = 0.8
"""P1: the two shares must meet their goals in at least this share of the runs (8 of 10)."""
P2_SHARE = 0.80
"""P2: at least this share of the answered requests where the learner's own value is lower."""


def arm_of(spec: RunSpec) -> str | None:
    """The arm an SGIM-ACTS run belongs to; None for another learner."""
    if spec.learner != SGIM_ACTS:
        return None
    params = {k: yaml.safe_load(v) for k, v in spec.params}
    return ARMS[(params.get("strategy_choice_order", "pair"),
                 params.get("strategy_value", "interest"))]


def same_teachers(specs: dict[str, RunSpec]) -> str | None:
    """The group of SGIM-D with SGIM-ACTS's teachers taking turns."""
    return next((g for g, s in specs.items()
                 if s.learner == SGIM_D and "teacher_turns" in dict(s.params)), None)


@dataclass(frozen=True)
class Arm:
    """One arm's runs (seed order) and what the page says of them."""

    name: str
    group: str
    runs: list[RunData]
    shares: acts_choices.ChoiceShares

    @property
    def requests(self) -> list[int]:
        return [len(r.ask_index) for r in self.runs]

    def both_goals(self) -> list[bool]:
        """Per run: expert share at least its goal and rough's share below its goal."""
        return [e.value is not None and e.value >= acts_choices.EXPERT_SHARE_GOAL
                and r.value is not None and r.value < acts_choices.ROUGH_SHARE_GOAL
                for e, r in zip(self.shares.expert, self.shares.rough, strict=True)]


def arms_of(study: Study, specs: dict[str, RunSpec], last: int) -> list[Arm]:
    arms = []
    for group, spec in specs.items():
        name = arm_of(spec)
        if name is not None:
            runs = study.runs_of(group)
            arms.append(Arm(name, group, runs, acts_choices.choice_shares(runs, last)))
    order = list(ARMS.values())
    return sorted(arms, key=lambda a: order.index(a.name))


def error_tests(numbers: StudyNumbers, arms: list[Arm], turns: str) -> dict[str, PairTest]:
    """Each arm against SGIM-D with the same teachers, Holm-corrected together."""
    finals = {g: numbers.finals[g].values for g in [*(a.group for a in arms), turns]}
    return {t.a: t for t in compare_groups(finals, [(a.group, turns) for a in arms])}


def _worse(test: PairTest) -> bool:
    return test.significant and test.closer == test.b


def _pooled(shares: list[Share]) -> str:
    pooled = acts_choices.ChoiceShares.pooled(shares)
    return f"{percent(pooled.value)} ({pooled.hits} of {pooled.total})"


def arms_table(arms: list[Arm], numbers: StudyNumbers, tests: dict[str, PairTest],
               demos: dict[str, list[int]], last: int) -> str:
    rows = []
    for arm in arms:
        i, t = numbers.finals[arm.group].interval, tests[arm.group]
        e_runs = sum(s.value is not None and s.value >= acts_choices.EXPERT_SHARE_GOAL
                     for s in arm.shares.expert)
        r_runs = sum(s.value is not None and s.value < acts_choices.ROUGH_SHARE_GOAL
                     for s in arm.shares.rough)
        land = land_share(arm.runs, last)
        rows.append([f"**{arm.name}**" if arm.name == BOTH else arm.name,
                     f"{num(i.mean)} [{num(i.low)}, {num(i.high)}]",
                     f"{num(t.difference.estimate)} ({'worse' if _worse(t) else 'no'})",
                     num(float(np.mean(arm.requests)), 1),
                     num(float(np.mean(demos[arm.group])), 1),
                     f"{_pooled(arm.shares.expert)}; {e_runs} of {len(arm.runs)} runs",
                     f"{_pooled(arm.shares.rough)}; {r_runs} of {len(arm.runs)} runs",
                     f"{percent(land.value)} ({land.hits} of {land.total})"])
    n = len(arms[0].runs) if arms else 0
    return "\n".join(table(
        ["SGIM-ACTS arm", "final error [95 % interval]",
         "minus SGIM-D with the same teachers (significantly worse?)", "requests per run",
         "demonstrations per run", f"expert share (runs at least "
         f"{percent(acts_choices.EXPERT_SHARE_GOAL)})",
         f"rough's share (runs below {percent(acts_choices.ROUGH_SHARE_GOAL)})",
         "requests about land"], rows)) + (
        f"\n{n} seeds per arm. The shares are those of the goals table, over the last {last} "
        "movements of each run, pooled over the runs, with the number of runs meeting each "
        "goal; 'worse': both Holm-corrected tests (Welch, Mann-Whitney; each arm against SGIM-D "
        f"with the same teachers, the {len(arms)} comparisons corrected together) find the "
        "arm significantly farther from the benchmark goals.")


def land_share(runs: Sequence[RunData], last: int) -> Share:
    """The requests of the runs' last movements about a goal on land, pooled."""
    return strategy_choices.land_share(
        (a for r in runs for a in acts_choices.last_asks(r, last)), acts_choices.part_of_outcome())


def shares_over_time(arm: Arm, window: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per window of movements: its middle, the expert share and rough's share, pooled over
    the arm's runs (NaN where no request counts)."""
    part_of = acts_choices.part_of_outcome()
    movements = max((r.total_movements for r in arm.runs), default=0)
    starts = np.arange(0, movements, window)
    by_window: list[list[Ask]] = [[] for _ in starts]
    for run in arm.runs:
        for ask in asks_from_run(run):
            k = min(ask.movement // window, len(starts) - 1)
            by_window[k].append(ask)
    expert = [expert_share(a, FISHING_EXPERTS, part_of).value for a in by_window]
    rough = [teacher_share(a, acts_choices.ROUGH).value for a in by_window]
    return starts + window / 2, _with_nan(expert), _with_nan(rough)


def _with_nan(values: list[float | None]) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def draw(arms: list[Arm], folder: Path, window: int) -> Path:
    curves = {arm.name: shares_over_time(arm, window) for arm in arms}
    return figures.plot_share_curves(
        curves, {"expert share": acts_choices.EXPERT_SHARE_GOAL,
                 "rough's share": acts_choices.ROUGH_SHARE_GOAL}, window, folder / FIGURE)


# --- P2: the values behind the requests ------------------------------------------------------

def choice_values(arm: Arm, specs: Sequence[RunSpec], behaviours: dict[str, str],
                  folder: Path, parallel: int = 2) -> dict[str, dict[str, np.ndarray]]:
    """Per run of the arm: the values of its choices, kept in `folder` (shipped beside the run
    tables) or replayed, checked against the run, and kept there."""
    by_name = {s.name: s for s in specs}
    found, todo = {}, []
    for run in arm.runs:
        kept = acts_values.load(acts_values.values_path(folder, run.name),
                                behaviours.get(run.name, ""))
        if kept is None:
            todo.append(run)
        else:
            found[run.name] = kept
    if todo:
        say(f"replaying {len(todo)} {arm.name} run(s) for the values behind "
                         "their requests (minutes each)")
        with ProcessPoolExecutor(max_workers=parallel, mp_context=get_context("spawn")) as pool:
            replays = pool.map(acts_values.replay, [by_name[r.name] for r in todo])
            for run, values in zip(todo, replays, strict=True):
                acts_values.check_same_run(values, run)
                if run.name in behaviours:
                    acts_values.save(acts_values.values_path(folder, run.name), values,
                                     behaviours[run.name])
                found[run.name] = values
    return found


def lower_own_value(values: dict[str, np.ndarray]) -> Share:
    """Of the answered requests, those whose leaf valued the learner's own strategy below the
    pair that asked."""
    social = np.char.find(values["strategy"].astype(str), ":") >= 0
    answered = social & values["answered"].astype(bool)
    return Share(int(np.sum(values["own"][answered] < values["value"][answered])),
                 int(answered.sum()))


# --- the predictions ---------------------------------------------------------------------------

def predictions(arms: list[Arm], tests: dict[str, PairTest], demos: dict[str, list[int]],
                turns: str, values: dict[str, dict[str, np.ndarray]]) -> list[Verdict]:
    both = next((a for a in arms if a.name == BOTH), None)
    if both is None:
        return []
    met_runs = both.both_goals()
    needed = math.ceil(P1_RUNS * len(met_runs) - 1e-9)
    p1 = Verdict(f"P1: with (A)+(B), the expert share at least "
                 f"{percent(acts_choices.EXPERT_SHARE_GOAL)} and rough's share below "
                 f"{percent(acts_choices.ROUGH_SHARE_GOAL)} in at least {needed} of the "
                 f"{len(met_runs)} runs",
                 f"both in {sum(met_runs)} of {len(met_runs)} runs (expert share pooled "
                 f"{_pooled(both.shares.expert)}, rough's {_pooled(both.shares.rough)})",
                 sum(met_runs) >= needed)
    per_run = [lower_own_value(values[r.name]) for r in both.runs if r.name in values]
    pooled = acts_choices.ChoiceShares.pooled(per_run)
    spread = [s.value for s in per_run if s.value is not None]
    p2 = Verdict(f"P2: at least {percent(P2_SHARE)} of the answered requests in leaves where "
                 "the learner's own gain is below the value of the pair that asked",
                 f"pooled {percent(pooled.value)} ({pooled.hits} of {pooled.total} answered "
                 f"requests); per run {percent(min(spread)) if spread else 'n/a'} to "
                 f"{percent(max(spread)) if spread else 'n/a'}",
                 None if pooled.value is None else pooled.value >= P2_SHARE)
    t = tests[both.group]
    p3 = Verdict("P3: with (A)+(B), a final error not significantly worse than SGIM-D's with "
                 "the same teachers",
                 f"difference {num(t.difference.estimate)} [{num(t.difference.low)}, "
                 f"{num(t.difference.high)}], Holm-corrected p: Welch {pval(t.welch_p_holm)}, "
                 f"Mann-Whitney {pval(t.mann_whitney_p_holm)}",
                 None if not t.applicable else not _worse(t))
    mine, theirs = float(np.mean(demos[both.group])), float(np.mean(demos[turns]))
    p4 = Verdict("P4: with (A)+(B), no more demonstrations per run than SGIM-D with the same "
                 "teachers takes",
                 f"{num(mine, 1)} per run against {num(theirs, 1)}", mine <= theirs)
    return [p1, p2, p3, p4]


def predictions_table(judged: list[Verdict]) -> str:
    word = {True: "held", False: "failed", None: "cannot be judged"}
    rows = [[v.goal, v.measured, f"**{word[v.met]}**"] for v in judged]
    return "\n".join(table(["prediction, as pinned", "what the runs gave", "held?"], rows)) + (
        "\nP2's values are not in the bags: they come from replaying each (A)+(B) run with the "
        "single-process runner, whose movements were checked to be the run's, one by one "
        "([`acts_values.py`](../sgim_nodes/sgim_nodes/experiments/acts_values.py)); the "
        "learner's own gain is the autonomous pair's in the leaf of the request's goal.")


def goal_verdicts(arms: list[Arm], judged: list[Verdict], last: int) -> list[Verdict]:
    """The issue's four goals for (A)+(B), as the goals table states them: its two shares
    (judged on the pooled shares, as today's choice is), no worse than SGIM-D with the same
    teachers (P3) and no more demonstrations (P4)."""
    both = next((a for a in arms if a.name == BOTH), None)
    if both is None or len(judged) < 4:
        return []
    shares = [Verdict(f"{BOTH}: {v.goal}", v.measured, v.met)
              for v in acts_choices.verdicts(both.shares, last)]
    return [*shares, *(Verdict(f"{BOTH}: {v.goal.partition(', ')[2]}", v.measured, v.met)
                       for v in judged[2:])]
