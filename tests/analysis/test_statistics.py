"""The study's numbers against values computed by hand (and p-values straight from scipy)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from synthetic_study import AT_0, AT_10, FINALS

from sgim_nodes.analysis.inference import holm
from sgim_nodes.analysis.statistics import (
    Coverage,
    RunCoverage,
    compare,
    coverage_tests,
    demonstration_times,
    error_curves,
    final_errors,
    isolated_coverage,
    mean_ci,
    pairwise_tests,
    run_summaries,
)
from sgim_nodes.analysis.study import load_study

T_975_DF2 = 4.302652729911275  # Student's t, 97.5 % quantile, 2 degrees of freedom (tables)


def test_mean_ci_by_hand() -> None:
    ci = mean_ci([0.20, 0.25, 0.30])  # sd = 0.05
    half = T_975_DF2 * 0.05 / math.sqrt(3)
    assert ci.mean == pytest.approx(0.25) and ci.n == 3
    assert ci.low == pytest.approx(0.25 - half) and ci.high == pytest.approx(0.25 + half)
    assert ci.half_width == pytest.approx(half)


def test_mean_ci_with_one_or_no_value_has_no_interval() -> None:
    one = mean_ci([0.3])
    assert one.mean == pytest.approx(0.3) and one.low is None and one.high is None
    assert one.half_width is None
    assert mean_ci([]).mean is None and mean_ci([float("nan")]).n == 0


def test_error_curves_at_every_evaluation_point(study: Path) -> None:
    curves = error_curves(load_study(study))
    c = curves["sgim-d"]
    assert c.movements.tolist() == [0, 10, 20]
    assert c.mean.tolist() == pytest.approx([AT_0, 0.42, 0.25])
    assert c.n.tolist() == [3, 3, 3]
    half_10 = T_975_DF2 * 0.02 / math.sqrt(3)  # AT_10 sgim-d: 0.40, 0.44, 0.42 -> sd 0.02
    assert c.low[1] == pytest.approx(0.42 - half_10) and c.high[1] == pytest.approx(0.42 + half_10)
    assert c.low[0] == pytest.approx(AT_0) and c.high[0] == pytest.approx(AT_0)  # no spread
    assert curves["random"].mean[1] == pytest.approx(sum(AT_10["random"]) / 3)


def test_final_errors_and_pairwise_tests_match_scipy(study: Path) -> None:
    finals = final_errors(load_study(study))
    assert finals["sgim-d"].values == pytest.approx(FINALS["sgim-d"])
    assert finals["random"].interval.mean == pytest.approx(0.5666666666)
    assert finals["sgim-d"].movements == [20, 20, 20]
    [test] = pairwise_tests(finals)
    welch = stats.ttest_ind(FINALS["sgim-d"], FINALS["random"], equal_var=False)
    mwu = stats.mannwhitneyu(FINALS["sgim-d"], FINALS["random"], alternative="two-sided")
    assert (test.a, test.b, test.closer) == ("sgim-d", "random", "sgim-d")
    assert test.mean_difference == pytest.approx(0.25 - 0.5666666666)
    assert test.welch_p == pytest.approx(welch.pvalue) and test.welch_t == pytest.approx(
        welch.statistic)
    assert test.mann_whitney_u == 0.0 and test.mann_whitney_p == pytest.approx(mwu.pvalue)
    assert test.mann_whitney_p == pytest.approx(0.1)  # 2 / C(6, 3): complete separation
    assert test.applicable and not test.significant  # MW cannot go below 0.1 with 3 vs 3


def test_tests_are_not_applicable_with_one_run() -> None:
    t = compare("a", [0.2], "b", [0.4, 0.5])
    assert not t.applicable and t.welch_p is None and t.mann_whitney_p is None
    assert t.closer == "a" and t.mean_difference == pytest.approx(-0.25)


def test_isolated_region_coverage_counts(study: Path) -> None:
    coverage = isolated_coverage(load_study(study))
    sgim = coverage["sgim-d"]
    first = sgim.runs[0]
    assert (first.outcomes, first.in_region, first.own_in_region) == (19, 3, 2)
    assert first.first_movement == 5 and first.share == pytest.approx(3 / 19)
    assert [r.in_region for r in sgim.runs] == [3, 0, 0]
    assert sgim.runs_reached == 1 and sgim.first_movement_median == 5
    assert sgim.share.mean == pytest.approx(1 / 19)
    assert coverage["random"].runs_reached == 0
    assert coverage["random"].first_movement_median is None


def test_run_summaries_from_metadata(study: Path) -> None:
    summary = run_summaries(load_study(study))["random"]
    assert (summary.runs, summary.finished, summary.seeds) == (3, 3, [0, 1, 2])
    assert summary.total_duration_s == pytest.approx(33.0)
    assert summary.mean_duration_s == pytest.approx(11.0)
    assert summary.demonstrations == [0, 0, 0]  # the synthetic study has no teacher


def _coverage(learner: str, own: list[int], outcomes: int = 1000) -> Coverage:
    return Coverage(learner, [RunCoverage(seed, outcomes, n + 1 if n else 0, n,
                                          100 if n else None) for seed, n in enumerate(own)])


def test_isolated_region_tests_match_scipy() -> None:
    coverage = {"sgim-d": _coverage("sgim-d", [5, 9, 0, 12, 7, 3]),
                "saggriac": _coverage("saggriac", [0, 0, 1, 0, 0, 0]),
                "random": _coverage("random", [0, 0, 0, 0, 0, 0])}
    tests = {(t.a, t.b): t for t in coverage_tests(coverage)}
    assert set(tests) == {("sgim-d", "saggriac"), ("sgim-d", "random"), ("saggriac", "random")}
    t = tests["sgim-d", "saggriac"]
    assert (t.reached_a, t.runs_a, t.reached_b, t.runs_b) == (5, 6, 1, 6)
    assert t.fisher_p == pytest.approx(stats.fisher_exact([[5, 1], [1, 5]]).pvalue)
    mwu = stats.mannwhitneyu([n / 1000 for n in (5, 9, 0, 12, 7, 3)],
                             [n / 1000 for n in (0, 0, 1, 0, 0, 0)], alternative="two-sided")
    assert t.own_share_p == pytest.approx(mwu.pvalue) and t.own_share_u == mwu.statistic
    assert t.own_share_p < 0.05  # MW p about 0.02 alone, but the table holds 6 p-values:
    ps = [p for u in tests.values() for p in (u.fisher_p, u.own_share_p)]
    assert t.own_share_p_holm == pytest.approx(holm(ps)[ps.index(t.own_share_p)])
    assert t.own_share_p_holm > 0.05 and not t.significant  # after Holm's correction
    assert t.fisher_min_p == pytest.approx(2 / math.comb(12, 6))  # 6/6 against 0/6
    assert t.reached_difference.estimate == pytest.approx(4 / 6)
    nothing = tests["saggriac", "random"]
    assert nothing.fisher_p == pytest.approx(1.0) and not nothing.significant
    # Nobody reached it in either: nothing to rank, no difference.
    none = coverage_tests({"a": _coverage("a", [0, 0]), "b": _coverage("b", [0, 0, 0])})[0]
    assert none.own_share_p == 1.0 and not none.significant
    one = coverage_tests({"a": _coverage("a", [4]), "b": _coverage("b", [0, 0])})[0]
    assert not one.applicable and one.fisher_p is None and not one.significant


class _Runs:
    def __init__(self, runs: dict[str, list]) -> None:
        self.learners, self._runs = list(runs), runs

    def runs_of(self, learner: str) -> list:
        return self._runs[learner]


class _Run:
    """A run's demonstration columns: {movement count: what it showed}, "both" or "means"
    (means-only: no outcome, a NaN row). The teacher's "nothing to show" turns are not among a
    run's records (RunRecords.learner_demonstrations), so they are simply absent here."""

    def __init__(self, given: dict[int, str], seed: int = 0) -> None:
        self.seed, self.finished, self.movements_done, self.duration_s = seed, True, 450, 9.0
        self.demo_index = np.array(list(given), dtype=np.int64)
        self.demo_outcome = np.array([[0.1, 0.2] if shown == "both" else [np.nan, np.nan]
                                      for shown in given.values()]).reshape(-1, 2)


def test_demonstration_times_count_every_shown_demonstration_per_run() -> None:
    # Seed 1 had nothing shown at 150 and a means-only demonstration (no outcome) at 300;
    # random got none at all.
    study = _Runs({"sgim-d": [_Run({0: "both", 150: "both"}), _Run({0: "both", 300: "means"})],
                   "random": [_Run({}), _Run({})]})
    times = demonstration_times(study)
    assert list(times) == ["sgim-d"]
    assert times["sgim-d"].movements.tolist() == [0, 150, 300]
    assert times["sgim-d"].runs_with_one.tolist() == [2, 1, 1]
    assert times["sgim-d"].runs == 2


def test_run_summaries_count_each_runs_shown_demonstrations() -> None:
    study = _Runs({"sgim-d": [_Run({0: "both", 150: "both"}, seed=0),
                              _Run({0: "means", 300: "means"}, seed=1)],
                   "random": [_Run({}, seed=0)]})
    summaries = run_summaries(study)
    assert summaries["sgim-d"].demonstrations == [2, 2]
    assert summaries["random"].demonstrations == [0]


def test_separate_time_frames_hold_each_landing_once(study: Path) -> None:
    from sgim_nodes.analysis.figures import _landings, frame_bounds

    assert frame_bounds([5, 10, 20], cumulative=True) == [(0, 5), (0, 10), (0, 20)]
    assert frame_bounds([5, 10, 20], cumulative=False) == [(0, 5), (5, 10), (10, 20)]
    runs = load_study(study).runs_of("sgim-d")
    separate = [len(_landings(runs, a, b)) for a, b in frame_bounds([5, 10, 20], False)]
    # 3 runs x movements 1..20, movement 7 failed in each: 3 x 19 landings in all.
    assert separate == [15, 12, 30] and sum(separate) == 57
    assert len(_landings(runs, 0, 20)) == 57
