"""The paper's second finding at 20 seeds, judged as pinned in docs/results.md ("The second
finding at 20 seeds"): S1-S4 on the page's own corrected tables, and the new seeds alone.

S1 reads the pairwise table of all learners (study_numbers' tests), S2-S4 the goal groups'
table (goal_groups' tests); S5 takes only the seeds added to decide it (NEW_SEEDS), which
played no part in writing S1-S4, and asks only for the signs of the differences.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sgim_nodes.analysis.report import StudyNumbers, num, pval, table
from sgim_nodes.analysis.statistics import PairTest, find_test
from sgim_nodes.core.learner_registry import DEMO_ONLY, SGIM_D
from sgim_nodes.experiments.reports.acts_choices import Verdict

NEW_SEEDS = range(10, 20)
"""The seeds of SGIM-D and demonstrations only added to decide the finding."""
GROUP_NAMES = {"all": "all goals", "far": "the goals farther than 0.1 from every demonstrated "
               "outcome", "near": "the goals within 0.1 of one", "pond": "the isolated "
               "region's goals"}


def difference(test: PairTest, a: str) -> float:
    """mean(a) - mean(the other) of a two-sided test, whichever side `a` is on."""
    return test.difference.estimate if test.a == a else -test.difference.estimate


def _said(test: PairTest, a: str) -> str:
    return (f"difference SGIM-D minus demonstrations only {num(difference(test, a))}, "
            f"Holm-corrected p: Welch {pval(test.welch_p_holm)}, Mann-Whitney "
            f"{pval(test.mann_whitney_p_holm)}")


def judge(overall: PairTest | None, by_group: dict[str, PairTest | None],
          new_seeds: dict[str, float | None]) -> list[Verdict]:
    """S1-S5 (module docstring). `by_group`: 'far', 'near', 'pond' -> the goal groups' test
    of SGIM-D against demonstrations only (its labels are 'sgim-d (far)' and so on);
    `new_seeds`: 'all', 'far', 'near' -> SGIM-D minus demonstrations only over NEW_SEEDS."""
    out = []
    if overall is not None:
        closer = overall.significant and overall.closer == SGIM_D
        out.append(Verdict("S1, all goals: SGIM-D not significantly closer, the difference "
                           "positive", _said(overall, SGIM_D),
                           not closer and difference(overall, SGIM_D) > 0))
    expect = {"far": ("S2", "SGIM-D significantly closer", SGIM_D),
              "near": ("S3", "demonstrations only significantly closer", DEMO_ONLY),
              "pond": ("S4", "no significant difference", None)}
    for group, (name, what, winner) in expect.items():
        test = by_group.get(group)
        if test is None:
            continue
        a = f"{SGIM_D} ({group})"
        met = (not test.significant if winner is None
               else test.significant and test.closer == f"{winner} ({group})")
        out.append(Verdict(f"{name}, {GROUP_NAMES[group]}: {what}", _said(test, a), met))
    signs = {"all": 1.0, "far": -1.0, "near": 1.0}
    found = {g: v for g, v in new_seeds.items() if v is not None and g in signs}
    if found:
        out.append(Verdict(
            "S5, seeds 10-19 alone: the differences of S1, S2 and S3 have the predicted signs "
            "(positive, negative, positive)",
            "; ".join(f"{GROUP_NAMES[g]} {num(v)}" for g, v in found.items())
            + " (SGIM-D minus demonstrations only, means over the ten seeds, uncorrected)",
            all(np.sign(v) == signs[g] for g, v in found.items())))
    return out


def new_seed_differences(groups: Any) -> dict[str, float | None]:
    """Per goal group, SGIM-D's mean minus demonstrations only's over NEW_SEEDS; `groups` is
    study.GoalGroups (its values and seeds)."""
    out: dict[str, float | None] = {}
    for group in ("all", "far", "near"):
        means = []
        for learner in (SGIM_D, DEMO_ONLY):
            found = groups.values[group].get(learner)
            values = [] if not found else [
                v for v, seed in zip(found, groups.seeds[learner], strict=True)
                if seed in NEW_SEEDS]
            means.append(float(np.mean(values)) if values else None)
        out[group] = None if None in means else means[0] - means[1]
    return out


def block(numbers: StudyNumbers, groups: Any) -> str:
    """The page's block (`groups`: study.GoalGroups): each pinned prediction, what the runs
    gave, held or failed."""
    overall = find_test(numbers.tests, SGIM_D, DEMO_ONLY)
    by_group = {g: find_test(groups.tests, f"{SGIM_D} ({g})", f"{DEMO_ONLY} ({g})")
                for g in ("far", "near", "pond")}
    judged = judge(overall, by_group, new_seed_differences(groups))
    n = {learner: len(groups.seeds.get(learner, [])) for learner in (SGIM_D, DEMO_ONLY)}
    word = {True: "held", False: "failed", None: "cannot be judged"}
    rows = [[v.goal, v.measured, f"**{word[v.met]}**"] for v in judged]
    return "\n".join(table(["prediction, as pinned", "what the runs gave", "held?"], rows)) + (
        f"\nSGIM-D {n[SGIM_D]} runs, demonstrations only {n[DEMO_ONLY]}; S1 from the pairwise "
        "table, S2-S4 from the goal groups' table, each corrected over its own table as the "
        "page does.")
