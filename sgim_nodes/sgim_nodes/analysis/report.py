"""A study's tables as named Markdown blocks, the one source of results.md and of the pages.

Why one source: the documentation's pages are generated from `analyze`'s numbers by another
tool, and results.md is written by `analyze` itself; both take their tables from blocks()
here, so a page and its study's results.md cannot drift apart. The blocks:

  final-errors       per group: n, demonstrations per run, mean final error, 95 % interval,
                     above the floor, per seed
  error-curve        mean error at the usual movement counts, lowest of each column in bold
  pairwise           the pairwise tests of final errors (Holm-corrected, effects, intervals)
  isolated-coverage  per group: runs reaching the isolated region, landings, first landings
  isolated-tests     the pairwise tests of isolated-region coverage (Holm-corrected)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from sgim_nodes.analysis.floor import FloorSummary
from sgim_nodes.analysis.inference import Effect
from sgim_nodes.analysis.pooling import check_alike
from sgim_nodes.analysis.statistics import (
    ALPHA,
    CONFIDENCE,
    Coverage,
    CoverageTest,
    Curve,
    FinalErrors,
    PairTest,
    RunSummary,
    compare_groups,
    coverage_tests,
    error_curves,
    final_errors,
    isolated_coverage,
    pairwise_tests,
    run_summaries,
)
from sgim_nodes.analysis.study import Study

CURVE_POINTS = (250, 500, 1000, 1500, 2000, 2500, 3000, 4000, 5000)
"""The error-curve block's columns when the runs were evaluated there (the paper's study)."""
BLOCKS = ("final-errors", "error-curve", "pairwise", "isolated-coverage", "isolated-tests")
PCT = round(CONFIDENCE * 100)


@dataclass
class StudyNumbers:
    """Everything the tables show, computed once (results.json holds the same)."""

    curves: dict[str, Curve]
    finals: dict[str, FinalErrors]
    tests: list[PairTest]
    coverage: dict[str, Coverage]
    region_tests: list[CoverageTest]
    summaries: dict[str, RunSummary]
    floor: FloorSummary | None = None


def study_numbers(study: Study, floor: FloorSummary | None = None) -> StudyNumbers:
    finals, coverage = final_errors(study), isolated_coverage(study)
    return StudyNumbers(error_curves(study), finals, pairwise_tests(finals), coverage,
                        coverage_tests(coverage), run_summaries(study), floor)


def num(value: float | None, digits: int = 3) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def pval(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.2g}" if value >= 1e-3 else f"{value:.1e}"


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header),
            *("| " + " | ".join(r) + " |" for r in rows), ""]


def _effect(e: Effect, digits: int = 3, signed: bool = True) -> str:
    shown = (lambda v: "n/a" if v is None else f"{v:+.{digits}f}") if signed else \
        (lambda v: num(v, digits))
    if e.estimate is None:
        return "n/a"
    interval = "" if e.low is None else f" [{shown(e.low)}, {shown(e.high)}]"
    return shown(e.estimate) + interval


def _compact(values: Sequence[object]) -> str:
    """One value when every run has it, else the list."""
    return str(values[0]) if values and len(set(values)) == 1 else ", ".join(map(str, values))


def _bold_lowest(cells: list[str]) -> list[str]:
    shown = [float(c) for c in cells if c not in ("n/a", "")]
    low = min(shown, default=None)
    return [f"**{c}**" if low is not None and c not in ("n/a", "") and float(c) == low
            and len(shown) > 1 else c for c in cells]


def final_errors_table(finals: Mapping[str, FinalErrors], summaries: Mapping[str, RunSummary],
                       floor: FloorSummary | None = None) -> str:
    """Per group: its runs' final errors, their mean with its interval, the floor."""
    moves = sorted({m for f in finals.values() for m in f.movements})
    at = f" (movement {moves[0]})" if len(moves) == 1 else ""
    header = ["learner", "n", *([] if at else ["at movement"]), "demonstrations per run",
              f"mean final error{at}", f"{PCT} % interval",
              *([] if floor is None else ["above the floor"]), "per seed"]
    means = _bold_lowest([num(f.interval.mean) for f in finals.values()])
    rows = []
    for f, mean in zip(finals.values(), means, strict=True):
        summary = summaries.get(f.learner)
        demos = dict(zip(summary.seeds, summary.demonstrations, strict=True)) if summary else {}
        rows.append([f.learner, str(f.interval.n),
                     *([] if at else [_compact(f.movements)]),
                     _compact([demos.get(s, "?") for s in f.seeds]), mean,
                     f"[{num(f.interval.low)}, {num(f.interval.high)}]",
                     *([] if floor is None else [num(f.interval.mean - floor.mean)]),
                     ", ".join(f"{v:.3f}" for v in f.values)])
    if floor is not None:
        rows.append(["floor (map lookup)", "", *([] if at else [""]), "", num(floor.mean),
                     "", "", ""])
    return "\n".join(table(header, rows)).rstrip()


def curve_points(curves: Mapping[str, Curve]) -> list[int]:
    """CURVE_POINTS the runs were evaluated at; else every evaluation count but the first."""
    have = sorted({int(m) for c in curves.values() for m in c.movements})
    usual = [p for p in CURVE_POINTS if p in have]
    return usual or [p for p in have if p > 0] or have


def error_curve_table(curves: Mapping[str, Curve], points: Sequence[int] | None = None) -> str:
    """Mean error over seeds at the given movement counts; the lowest of each column bold."""
    points = list(points) if points is not None else curve_points(curves)
    columns = []
    for p in points:
        cells = []
        for c in curves.values():
            where = np.flatnonzero(c.movements == p)
            cells.append(num(float(c.mean[where[0]])) if len(where) else "")
        columns.append(_bold_lowest(cells))
    rows = [[name, *(col[k] for col in columns)] for k, name in enumerate(curves)]
    return "\n".join(table(["movements", *map(str, points)], rows)).rstrip()


def _significant(test: PairTest | CoverageTest) -> str:
    return ("yes" if test.significant else "no") if test.applicable else "n/a"


def pairwise_markdown(tests: Sequence[PairTest]) -> str:
    """The corrected pairwise tests of final errors, as one table and its reading."""
    if not tests:
        return "No pair to compare."
    rows = [[t.a, t.b, f"{t.n_a}, {t.n_b}", _effect(t.difference), t.closer or "tie",
             pval(t.welch_p), pval(t.welch_p_holm), _effect(t.cliffs_delta, 2),
             pval(t.mann_whitney_p), pval(t.mann_whitney_p_holm), pval(t.mann_whitney_min_p),
             _significant(t)] for t in tests]
    m = sum(p is not None for t in tests for p in (t.welch_p, t.mann_whitney_p))
    out = table(["a", "b", "n (a, b)", f"mean(a) - mean(b) [{PCT} %]", "closer", "Welch p",
                 "Welch p (Holm)", f"Cliff's delta [{PCT} %]", "MW p", "MW p (Holm)",
                 "smallest MW p", "significant"], rows)
    out.append(
        f"Two-sided tests; Holm's correction over the {m} p-values of this table; "
        f"'significant' when both corrected p < {ALPHA}. Beside Welch's t: the difference of "
        f"the means with its Welch {PCT} % interval. Beside Mann-Whitney U (exact without "
        f"ties): Cliff's delta, P(a > b) - P(a < b), with Cliff's {PCT} % interval (-1: every "
        "run of a ends closer than every run of b). Smallest MW p: the lowest p the exact "
        "test can give at these n. n/a when a learner has fewer than 2 runs.")
    return "\n".join(out)


def pairwise_table(groups: Mapping[str, Sequence[float]],
                   pairs: Sequence[tuple[str, str]] | None = None) -> str:
    """pairwise_markdown of any groups' values (default: every pair), corrected together."""
    return pairwise_markdown(compare_groups(groups, pairs))


def isolated_coverage_table(coverage: Mapping[str, Coverage]) -> str:
    """Per group: how its runs met the isolated region."""
    rows = []
    for c in coverage.values():
        landings = [r.in_region for r in c.runs]
        own = [r.own_in_region for r in c.runs]
        share = c.share
        interval = "" if share.low is None else (  # a share lies in [0, 100] %
            f" [{num(max(0.0, 100 * share.low), 2)}, {num(min(100.0, 100 * share.high), 2)}]")
        rows.append([c.learner, f"{c.runs_reached}/{len(c.runs)}", ", ".join(map(str, landings)),
                     "the same" if own == landings else ", ".join(map(str, own)),
                     ", ".join("never" if r.first_movement is None else str(r.first_movement)
                               for r in c.runs), num(c.first_movement_median, 0),
                     f"{num(None if share.mean is None else 100 * share.mean, 2)} %{interval}"])
    return "\n".join(table(
        ["learner", "runs reaching it", "landings in it per run", "own landings per run",
         "first landing, per run", "median first", f"share of landings [{PCT} %]"],
        rows)).rstrip()


def isolated_tests_table(tests: Sequence[CoverageTest]) -> str:
    """The corrected pairwise tests of isolated-region coverage, and their reading."""
    if not tests:
        return "No pair to compare."
    rows = [[t.a, t.b, f"{t.reached_a}/{t.runs_a}, {t.reached_b}/{t.runs_b}",
             _effect(t.reached_difference, 2), pval(t.fisher_p), pval(t.fisher_p_holm),
             pval(t.fisher_min_p), _effect(t.own_share_delta, 2), pval(t.own_share_p),
             pval(t.own_share_p_holm), pval(t.own_share_min_p), _significant(t)]
            for t in tests]
    m = sum(p is not None for t in tests for p in (t.fisher_p, t.own_share_p))
    out = table(["a", "b", "runs reaching it (a, b)", f"share reaching a - b [{PCT} %]",
                 "Fisher p", "Fisher p (Holm)", "smallest Fisher p",
                 f"own share Cliff's delta [{PCT} %]", "MW p", "MW p (Holm)", "smallest MW p",
                 "significant"], rows)
    out.append(
        "Two-sided tests: Fisher's exact test on the runs reaching it, beside the difference "
        f"of the shares of runs reaching it (Newcombe's {PCT} % interval); Mann-Whitney U on "
        "each run's share of its own landings there, beside Cliff's delta (its "
        f"{PCT} % interval). Holm's correction over the {m} p-values of this table; "
        f"'significant' when either corrected p < {ALPHA}. Smallest p: the lowest each test "
        "can give at these n.")
    return "\n".join(out)


def render(numbers: StudyNumbers, points: Sequence[int] | None = None) -> dict[str, str]:
    """The blocks (BLOCKS, in that order) of numbers already computed."""
    return {
        "final-errors": final_errors_table(numbers.finals, numbers.summaries, numbers.floor),
        "error-curve": error_curve_table(numbers.curves, points),
        "pairwise": pairwise_markdown(numbers.tests),
        "isolated-coverage": isolated_coverage_table(numbers.coverage),
        "isolated-tests": isolated_tests_table(numbers.region_tests),
    }


def blocks(study: Study, floor: FloorSummary | None = None,
           points: Sequence[int] | None = None, allow_mixed: bool = False) -> dict[str, str]:
    """A study's named Markdown blocks (BLOCKS), as results.md shows them. ``floor``: what
    final-errors compares against (floor.benchmark_floor() for the shipped benchmark; None:
    no floor column); ``points``: error-curve's columns (default curve_points). Raises
    pooling.MixedRunsError when the runs are not alike, unless ``allow_mixed``."""
    check_alike(study, allow_mixed)
    return render(study_numbers(study, floor), points)
