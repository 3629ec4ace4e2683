"""Holm's correction, the smallest reachable p and the effect sizes against values by hand."""

from __future__ import annotations

import math

import pytest
from scipy import stats

from sgim_nodes.analysis.inference import (
    cliffs_delta,
    holm,
    mann_whitney,
    min_p_fisher,
    min_p_mann_whitney,
    proportion_difference,
    welch_interval,
    wilson,
)
from sgim_nodes.analysis.statistics import compare_groups

Z_975 = 1.959963984540054


def test_holm_on_a_known_list() -> None:
    # Sorted: 0.005 x 4 = 0.02, 0.01 x 3 = 0.03, 0.03 x 2 = 0.06, 0.04 x 1 = 0.04 -> 0.06
    # (never below the one before).
    assert holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])  # capped at 1
    assert holm([0.02]) == pytest.approx([0.02])  # one test: nothing to correct
    # A test that could not be made is not counted among the tests.
    assert holm([None, 0.01, 0.04]) == [None, pytest.approx(0.02), pytest.approx(0.04)]
    assert holm([]) == []


def test_smallest_mann_whitney_p() -> None:
    assert min_p_mann_whitney(5, 5) == pytest.approx(2 / 252)  # 0.0079
    assert round(min_p_mann_whitney(5, 5), 4) == 0.0079
    assert min_p_mann_whitney(3, 3) == pytest.approx(0.1)  # 2 / C(6, 3): never below 0.1
    assert min_p_mann_whitney(10, 10) == pytest.approx(2 / 184756)
    assert min_p_mann_whitney(1, 1) == 1.0 and min_p_mann_whitney(0, 4) is None
    # It is what the exact test gives on separated samples.
    assert mann_whitney([1, 2, 3, 4, 5], [6, 7, 8, 9, 10])[1:] == (pytest.approx(2 / 252), True)


def test_smallest_fisher_p() -> None:
    # 3 runs against 3: the most extreme table, all against none, has p = 2 / C(6, 3).
    assert min_p_fisher(3, 3) == pytest.approx(0.1)
    assert min_p_fisher(5, 5) == pytest.approx(2 / 252)
    # 4 against 6: [[4, 0], [0, 6]] has probability 1 / C(10, 4) = 1/210, and the tables as
    # unlikely on the other side of the same margins (4 reaching it) have 15/210: p = 1/210.
    assert min_p_fisher(4, 6) == pytest.approx(1 / 210)
    assert min_p_fisher(0, 3) is None


def test_mann_whitney_is_exact_without_ties_only() -> None:
    u, p, exact = mann_whitney([0.1, 0.2, 0.3], [0.4, 0.5, 0.6])
    assert (u, exact) == (0.0, True) and p == pytest.approx(0.1)
    u, p, exact = mann_whitney([0.0, 0.0, 0.3], [0.0, 0.5, 0.6])
    assert not exact
    assert p == pytest.approx(stats.mannwhitneyu([0.0, 0.0, 0.3], [0.0, 0.5, 0.6],
                                                 method="asymptotic").pvalue)


def test_cliffs_delta_of_separated_samples_is_plus_or_minus_one() -> None:
    below = cliffs_delta([1, 2, 3, 4, 5], [6, 7, 8, 9, 10])
    assert below.estimate == -1.0 and below.low == -1.0 and -1.0 < below.high < 0.0
    above = cliffs_delta([6, 7, 8, 9, 10], [1, 2, 3, 4, 5])
    assert above.estimate == 1.0 and above.high == 1.0
    assert above.low == pytest.approx(-below.high)
    # More runs, a narrower interval.
    assert cliffs_delta(range(10), range(10, 20)).high < below.high


def test_cliffs_delta_by_hand() -> None:
    # Pairs (1,2) -, (1,3) -, (2,2) 0, (2,3) -: delta = -3/4.
    assert cliffs_delta([1, 2], [2, 3]).estimate == pytest.approx(-0.75)
    assert cliffs_delta([1.0], [2.0, 3.0]).low is None  # one value: no interval
    # R's effsize example (treatment against control): delta -0.25; the three terms of
    # Cliff's consistent variance are 0.2669753 (rows), 0.447 (columns) and 1.0055556
    # (pairs), so var = (5 x 0.2669753 + 9 x 0.447 + 1.0055556) / 60, and the interval is
    # (d - d^3 -+ z sqrt(var) sqrt((1 - d^2)^2 + z^2 var)) / (1 - d^2 + z^2 var).
    treatment = [10, 10, 20, 20, 20, 30, 30, 30, 40, 50]
    control = [10, 20, 30, 40, 40, 50]
    var = (5 * 0.26697530864 + 9 * 0.447 + 1.00555555556) / 60
    d, z = -0.25, Z_975
    root = z * math.sqrt(var) * math.sqrt((1 - d * d) ** 2 + z * z * var)
    low, high = ((d - d ** 3 + s * root) / (1 - d * d + z * z * var) for s in (-1, 1))
    effect = cliffs_delta(treatment, control, normal=True)
    assert effect.estimate == pytest.approx(-0.25)
    assert (effect.low, effect.high) == (pytest.approx(low), pytest.approx(high))
    # By default the quantile is Student's t with 14 degrees of freedom: a wider interval.
    wide = cliffs_delta(treatment, control)
    assert wide.low < effect.low and wide.high > effect.high


def test_welch_interval_by_hand() -> None:
    a, b = [0.20, 0.25, 0.30], [0.50, 0.55, 0.65]
    # var(a) = 0.005 / 2, var(b) = (0.0667^2 + 0.0167^2 + 0.0833^2) / 2 = 0.011667 / 2;
    # Welch-Satterthwaite degrees of freedom from var / n of each side.
    sa, sb = (0.005 / 2) / 3, (0.0116666667 / 2) / 3
    df = (sa + sb) ** 2 / (sa ** 2 / 2 + sb ** 2 / 2)
    half = stats.t.ppf(0.975, df) * math.sqrt(sa + sb)
    effect = welch_interval(a, b)
    assert effect.estimate == pytest.approx(0.25 - 0.5666666667)
    assert effect.low == pytest.approx(effect.estimate - half)
    assert effect.high == pytest.approx(effect.estimate + half)
    scipy_ci = stats.ttest_ind(a, b, equal_var=False).confidence_interval(0.95)
    assert (effect.low, effect.high) == (pytest.approx(scipy_ci.low), pytest.approx(scipy_ci.high))
    assert welch_interval([0.1, 0.1], [0.2, 0.2]).low is None  # no spread: no interval
    assert welch_interval([0.1], [0.2, 0.3]).estimate == pytest.approx(-0.15)


def test_difference_of_proportions_matches_newcombe() -> None:
    """Newcombe (1998), Statistics in Medicine 17: 873-890, Table II, method 10."""
    for (xa, na, xb, nb), (low, high) in {(56, 70, 48, 80): (0.0524, 0.3339),
                                          (9, 10, 3, 10): (0.1705, 0.8090),
                                          (10, 10, 0, 10): (0.6075, 1.0),
                                          (0, 10, 0, 10): (-0.2775, 0.2775)}.items():
        effect = proportion_difference(xa, na, xb, nb)
        assert effect.estimate == pytest.approx(xa / na - xb / nb)
        assert (effect.low, effect.high) == (pytest.approx(low, abs=5e-5),
                                             pytest.approx(high, abs=5e-5))
    # Wilson's interval of 0 of n ends at z^2 / (n + z^2).
    assert wilson(0, 10) == (0.0, pytest.approx(Z_975 ** 2 / (10 + Z_975 ** 2)))


def test_a_table_of_tests_is_corrected_as_one_family() -> None:
    groups = {"a": [0.10, 0.11, 0.12, 0.13, 0.14], "b": [0.20, 0.21, 0.22, 0.23, 0.24],
              "c": [0.12, 0.135, 0.15, 0.16, 0.17]}
    tests = compare_groups(groups)
    assert [(t.a, t.b) for t in tests] == [("a", "b"), ("a", "c"), ("b", "c")]
    raw = [p for t in tests for p in (t.welch_p, t.mann_whitney_p)]
    corrected = holm(raw)
    assert [p for t in tests for p in (t.welch_p_holm, t.mann_whitney_p_holm)] == corrected
    ab = tests[0]
    assert ab.mann_whitney_exact and ab.mann_whitney_p == pytest.approx(2 / 252)
    assert ab.mann_whitney_min_p == pytest.approx(2 / 252) and ab.cliffs_delta.estimate == -1
    assert ab.significant == (max(ab.welch_p_holm, ab.mann_whitney_p_holm) < 0.05)
    # A chosen subset of pairs is its own table.
    [only] = compare_groups(groups, [("b", "c")])
    assert [only.welch_p_holm, only.mann_whitney_p_holm] == holm([only.welch_p,
                                                                   only.mann_whitney_p])
    assert (only.a, only.b, only.n_a, only.n_b) == ("b", "c", 5, 5)
