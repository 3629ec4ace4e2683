"""The study's numbers: error over seeds, pairwise tests of final errors, isolated-region coverage.

Why these: the paper's claims are comparisons between learners (closer to the benchmark goals,
wider exploration), so every number comes with its spread over seeds. The interval is t-based
because a study has few seeds (10), where a normal interval would be too narrow. Two tests
are given for each pair: Welch's t (means, unequal variances) and Mann-Whitney U (ranks, no
normality assumed), since final errors of a few seeds are rarely normal. Each table of tests
is corrected as one family (Holm), and every p stands beside an effect with its interval and
the smallest p its test can reach at those n (inference.py). With one run on a side there is
no spread, so intervals and tests are reported as not applicable (None), not faked.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from itertools import combinations

import numpy as np
from scipy import stats

from sgim_nodes.analysis.inference import (
    CONFIDENCE,
    NO_EFFECT,
    Effect,
    cliffs_delta,
    holm,
    mann_whitney,
    min_p_fisher,
    min_p_mann_whitney,
    proportion_difference,
    welch_interval,
)
from sgim_nodes.analysis.study import (
    PROCESS_DEMONSTRATION,
    PROCESS_IMITATION,
    STATUS_OK,
    RunData,
    Study,
)
from sim_bridge.lake import in_isolated_region

ALPHA = 0.05


@dataclass(frozen=True)
class Interval:
    """Mean and two-sided t interval over n values; low/high are None when n < 2."""

    mean: float | None
    low: float | None
    high: float | None
    n: int

    @property
    def half_width(self) -> float | None:
        return None if self.low is None or self.high is None else (self.high - self.low) / 2


def mean_ci(values: np.ndarray | list[float], confidence: float = CONFIDENCE) -> Interval:
    """Mean of the finite values and its t interval: mean +- t(n-1) * sd / sqrt(n)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    n = len(v)
    if n == 0:
        return Interval(None, None, None, 0)
    mean = float(v.mean())
    if n < 2:
        return Interval(mean, None, None, n)
    half = float(stats.t.ppf(0.5 + confidence / 2, n - 1) * v.std(ddof=1) / math.sqrt(n))
    return Interval(mean, mean - half, mean + half, n)


@dataclass
class Curve:
    """One learner's error at every evaluation point (runs lacking a point are left out)."""

    learner: str
    movements: np.ndarray
    mean: np.ndarray
    low: np.ndarray  # NaN where fewer than 2 runs
    high: np.ndarray
    n: np.ndarray


def error_curves(study: Study) -> dict[str, Curve]:
    curves = {}
    for learner in study.learners:
        runs = [r for r in study.runs_of(learner) if len(r.eval_index)]
        if not runs:
            continue
        points = np.unique(np.concatenate([r.eval_index for r in runs]))
        rows = [mean_ci([r.eval_mean[r.eval_index == p][0] for r in runs if p in r.eval_index])
                for p in points]
        nan = float("nan")
        curves[learner] = Curve(
            learner, points, np.array([c.mean for c in rows], dtype=float),
            np.array([nan if c.low is None else c.low for c in rows]),
            np.array([nan if c.high is None else c.high for c in rows]),
            np.array([c.n for c in rows]))
    return curves


@dataclass
class FinalErrors:
    """Each run's last evaluation (the error after its whole budget, for a finished run)."""

    learner: str
    seeds: list[int]
    movements: list[int]  # movement count of each run's last evaluation
    values: list[float]
    interval: Interval


def final_errors(study: Study) -> dict[str, FinalErrors]:
    out = {}
    for learner in study.learners:
        runs = [r for r in study.runs_of(learner) if len(r.eval_index)]
        if runs:
            values = [float(r.eval_mean[-1]) for r in runs]
            out[learner] = FinalErrors(learner, [r.seed for r in runs],
                                       [int(r.eval_index[-1]) for r in runs], values,
                                       mean_ci(values))
    return out


@dataclass(frozen=True)
class PairTest:
    """Final errors of learner a against b: two tests, each beside its effect and interval.
    Welch's t with mean(a) - mean(b) and its Welch interval; Mann-Whitney U (exact without
    ties) with Cliff's delta and its interval, and the smallest p it can reach at these n.
    The *_holm p-values are corrected over the table the test is part of (pairwise_tests);
    p-values are None when either side has fewer than 2 runs."""

    a: str
    b: str
    n_a: int
    n_b: int
    mean_difference: float  # mean(a) - mean(b): negative when a ends closer to the goals
    closer: str  # the learner with the lower mean final error ("" on a tie)
    welch_t: float | None
    welch_p: float | None
    mann_whitney_u: float | None
    mann_whitney_p: float | None
    difference: Effect = NO_EFFECT  # mean(a) - mean(b), Welch interval
    cliffs_delta: Effect = NO_EFFECT  # -1: every run of a below every one of b
    mann_whitney_exact: bool = False
    mann_whitney_min_p: float | None = None  # the exact test's floor at n_a, n_b
    welch_p_holm: float | None = None
    mann_whitney_p_holm: float | None = None

    @property
    def applicable(self) -> bool:
        return self.welch_p is not None or self.mann_whitney_p is not None

    @property
    def significant(self) -> bool:
        """Both corrected p-values below ALPHA (the two tests agree)."""
        ps = [p for p in (self.welch_p_holm, self.mann_whitney_p_holm) if p is not None]
        return bool(ps) and max(ps) < ALPHA


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def compare(a: str, va: Sequence[float], b: str, vb: Sequence[float]) -> PairTest:
    """One pair, as a table of its own (the corrected p-values are the raw ones)."""
    va, vb = list(va), list(vb)
    diff = float(np.mean(va) - np.mean(vb))
    closer = a if diff < 0 else b if diff > 0 else ""
    base = dict(difference=welch_interval(va, vb), cliffs_delta=cliffs_delta(va, vb),
                mann_whitney_min_p=min_p_mann_whitney(len(va), len(vb)))
    if len(va) < 2 or len(vb) < 2:
        return PairTest(a, b, len(va), len(vb), diff, closer, None, None, None, None, **base)
    welch = stats.ttest_ind(va, vb, equal_var=False)  # NaN when both sides are constant
    u, mw_p, exact = mann_whitney(va, vb)
    welch_p = _finite(welch.pvalue)
    return PairTest(a, b, len(va), len(vb), diff, closer, _finite(welch.statistic), welch_p,
                    u, mw_p, mann_whitney_exact=exact, welch_p_holm=welch_p,
                    mann_whitney_p_holm=mw_p, **base)


def find_test(tests: Sequence[PairTest], a: str, b: str) -> PairTest | None:
    """The test of `a` against `b`, whichever side each is on; None when there is none."""
    return next((t for t in tests if {t.a, t.b} == {a, b}), None)


def compare_groups(groups: Mapping[str, Sequence[float]],
                   pairs: Sequence[tuple[str, str]] | None = None) -> list[PairTest]:
    """The given pairs (default: every pair, in the groups' order) as one table: Holm's
    correction over all its p-values, Welch's and Mann-Whitney's together."""
    pairs = list(combinations(list(groups), 2)) if pairs is None else list(pairs)
    tests = [compare(a, groups[a], b, groups[b]) for a, b in pairs]
    corrected = holm([p for t in tests for p in (t.welch_p, t.mann_whitney_p)])
    return [replace(t, welch_p_holm=corrected[2 * k], mann_whitney_p_holm=corrected[2 * k + 1])
            for k, t in enumerate(tests)]


def pairwise_tests(finals: dict[str, FinalErrors]) -> list[PairTest]:
    return compare_groups({k: f.values for k, f in finals.items()})


@dataclass
class RunCoverage:
    """How one run's outcomes met the isolated region (only valid outcomes count)."""

    seed: int
    outcomes: int  # movements with a valid outcome (STATUS_OK)
    in_region: int
    own_in_region: int  # of which not an imitation or the demonstration itself
    first_movement: int | None  # the first movement that landed there

    @property
    def share(self) -> float:
        return self.in_region / self.outcomes if self.outcomes else 0.0


@dataclass
class Coverage:
    learner: str
    runs: list[RunCoverage] = field(default_factory=list)

    @property
    def runs_reached(self) -> int:
        return sum(r.in_region > 0 for r in self.runs)

    @property
    def share(self) -> Interval:
        return mean_ci([r.share for r in self.runs])

    @property
    def first_movement_median(self) -> float | None:
        firsts = [r.first_movement for r in self.runs if r.first_movement is not None]
        return float(np.median(firsts)) if firsts else None


def run_coverage(run: RunData) -> RunCoverage:
    ok = (run.status == STATUS_OK) & np.isfinite(run.outcome).all(axis=1)
    inside = ok & in_isolated_region(np.nan_to_num(run.outcome, nan=9.0))
    own = inside & ~np.isin(run.process, [PROCESS_IMITATION, PROCESS_DEMONSTRATION])
    first = int(run.movement_index[inside].min()) if inside.any() else None
    return RunCoverage(run.seed, int(ok.sum()), int(inside.sum()), int(own.sum()), first)


def isolated_coverage(study: Study) -> dict[str, Coverage]:
    return {learner: Coverage(learner, [run_coverage(r) for r in study.runs_of(learner)])
            for learner in study.learners}


@dataclass(frozen=True)
class CoverageTest:
    """Do two learners meet the isolated region differently? Two views of the same question:
    how many runs reach it at all (Fisher's exact test on runs reaching / not reaching, beside
    the difference of the shares of runs reaching it), and how much of a run's own
    exploration lands there (Mann-Whitney U on the per-run share of landings that are the
    learner's own, imitations and demonstrated actions left out, beside Cliff's delta). The
    *_holm p-values are corrected over the table (coverage_tests)."""

    a: str
    b: str
    reached_a: int
    runs_a: int
    reached_b: int
    runs_b: int
    fisher_p: float | None
    own_share_u: float | None
    own_share_p: float | None
    reached_difference: Effect = NO_EFFECT  # Newcombe's interval
    own_share_delta: Effect = NO_EFFECT  # Cliff's delta of the own shares
    fisher_min_p: float | None = None
    own_share_min_p: float | None = None  # the exact Mann-Whitney test's floor
    fisher_p_holm: float | None = None
    own_share_p_holm: float | None = None

    @property
    def applicable(self) -> bool:
        return min(self.runs_a, self.runs_b) >= 2

    @property
    def significant(self) -> bool:
        """Either corrected p-value below ALPHA (the table's correction counts both)."""
        return self.applicable and any(p is not None and p < ALPHA
                                       for p in (self.fisher_p_holm, self.own_share_p_holm))


def own_share(run: RunCoverage) -> float:
    return run.own_in_region / run.outcomes if run.outcomes else 0.0


def _coverage_test(a: Coverage, b: Coverage) -> CoverageTest:
    na, nb = len(a.runs), len(b.runs)
    sa, sb = [own_share(r) for r in a.runs], [own_share(r) for r in b.runs]
    base = dict(reached_difference=proportion_difference(a.runs_reached, na,
                                                         b.runs_reached, nb),
                own_share_delta=cliffs_delta(sa, sb), fisher_min_p=min_p_fisher(na, nb),
                own_share_min_p=min_p_mann_whitney(na, nb))
    fisher_p = u = mw_p = None
    if min(na, nb) >= 2:
        table = [[a.runs_reached, na - a.runs_reached], [b.runs_reached, nb - b.runs_reached]]
        fisher_p = float(stats.fisher_exact(table).pvalue)
        if len(set(sa) | set(sb)) > 1:  # all equal (say, all zero): nothing to rank
            u, mw_p, _ = mann_whitney(sa, sb)
        else:
            u, mw_p = float(na * nb / 2), 1.0
    return CoverageTest(a.learner, b.learner, a.runs_reached, na, b.runs_reached, nb, fisher_p,
                        u, mw_p, fisher_p_holm=fisher_p, own_share_p_holm=mw_p, **base)


def coverage_tests(coverage: dict[str, Coverage],
                   pairs: Sequence[tuple[str, str]] | None = None) -> list[CoverageTest]:
    """The given pairs (default: every pair of learners; two-sided tests), Holm's correction
    over all the table's p-values, Fisher's and Mann-Whitney's together."""
    pairs = list(combinations(list(coverage), 2)) if pairs is None else list(pairs)
    tests = [_coverage_test(coverage[a], coverage[b]) for a, b in pairs]
    corrected = holm([p for t in tests for p in (t.fisher_p, t.own_share_p)])
    return [replace(t, fisher_p_holm=corrected[2 * k], own_share_p_holm=corrected[2 * k + 1])
            for k, t in enumerate(tests)]


@dataclass(frozen=True)
class DemonstrationTimes:
    """When a learner's runs were given demonstrations (non-empty ones): each movement count
    at which any run got one, and in how many of the ``runs`` runs."""

    movements: np.ndarray
    runs_with_one: np.ndarray
    runs: int


def _shown_demonstrations(run) -> np.ndarray:
    """The movement counts at which a run was shown a demonstration: its records are the
    demonstrations the learner took (RunRecords.learner_demonstrations: the teacher's "nothing
    to show" turns are never among them), whatever part they showed. A means-only one has no
    outcome (a NaN row in demo_outcome) and is counted all the same."""
    return np.unique(run.demo_index)


def demonstration_times(study: Study) -> dict[str, DemonstrationTimes]:
    """Learners whose runs got at least one demonstration."""
    out = {}
    for learner in study.learners:
        runs = study.runs_of(learner)
        given = [_shown_demonstrations(r) for r in runs]
        pooled = np.concatenate(given) if given else np.zeros(0, dtype=np.int64)
        if len(pooled):
            movements, counts = np.unique(pooled, return_counts=True)
            out[learner] = DemonstrationTimes(movements, counts, len(runs))
    return out


@dataclass
class RunSummary:
    """What the metadata says about a learner's runs: how many, finished, how long; and how
    many demonstrations each run was shown (issue 11: the teacher must keep teaching)."""

    learner: str
    runs: int
    finished: int
    seeds: list[int]
    movements: list[int]
    total_duration_s: float | None
    mean_duration_s: float | None
    demonstrations: list[int]


def run_summaries(study: Study) -> dict[str, RunSummary]:
    out = {}
    for learner in study.learners:
        runs = study.runs_of(learner)
        durations = [d for d in (r.duration_s for r in runs) if d is not None]
        out[learner] = RunSummary(
            learner, len(runs), sum(r.finished for r in runs), [r.seed for r in runs],
            [r.movements_done for r in runs], float(sum(durations)) if durations else None,
            float(np.mean(durations)) if durations else None,
            [len(_shown_demonstrations(r)) for r in runs])
    return out
