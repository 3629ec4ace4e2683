"""Pure statistics for tables of many tests: Holm's correction, the smallest p a test can
reach, and effect sizes with 95 % intervals.

Why: a table of ten pairwise comparisons at alpha 0.05 finds something by chance, so its
p-values are corrected together (Holm: as strong as Bonferroni's guarantee, never less
powerful). A p-value says nothing of how large a difference is, so each one stands beside an
effect with its interval. And with few runs a rank test cannot go below some p whatever the
data (3 runs against 3: 0.1), so the tables state that floor: a "not significant" there is
no evidence of no difference. Everything here is deterministic: no resampling.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np
from scipy import stats

CONFIDENCE = 0.95


@dataclass(frozen=True)
class Effect:
    """An effect and its interval; low/high are None when the data cannot give one."""

    estimate: float | None
    low: float | None
    high: float | None


NO_EFFECT = Effect(None, None, None)


def holm(pvalues: Sequence[float | None]) -> list[float | None]:
    """Holm's step-down adjusted p-values, in the given order (None stays None and is not
    counted among the tests): the k-th smallest of m is multiplied by m - k + 1, made
    non-decreasing, and capped at 1."""
    known = sorted((p, k) for k, p in enumerate(pvalues) if p is not None)
    m = len(known)
    out: list[float | None] = [None] * len(pvalues)
    running = 0.0
    for rank, (p, k) in enumerate(known):
        running = max(running, min(1.0, (m - rank) * p))
        out[k] = running
    return out


def min_p_mann_whitney(na: int, nb: int) -> float | None:
    """The smallest two-sided p of the exact Mann-Whitney U test with na and nb values: that of
    complete separation, 2 / C(na + nb, na) (None below 1 value a side)."""
    if na < 1 or nb < 1:
        return None
    return min(1.0, 2 / math.comb(na + nb, na))


@cache
def min_p_fisher(na: int, nb: int) -> float | None:
    """The smallest two-sided p of Fisher's exact test on a 2 x 2 table whose rows hold na and
    nb runs, over every split of each row (None below 1 run a row)."""
    if na < 1 or nb < 1:
        return None
    return min(float(stats.fisher_exact([[x, na - x], [y, nb - y]]).pvalue)
               for x in range(na + 1) for y in range(nb + 1))


def _finite(values: Sequence[float]) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return v[np.isfinite(v)]


def welch_interval(a: Sequence[float], b: Sequence[float],
                   confidence: float = CONFIDENCE) -> Effect:
    """mean(a) - mean(b) and its Welch interval (t with the Welch-Satterthwaite degrees of
    freedom); no interval with fewer than 2 values a side or no spread in either."""
    va, vb = _finite(a), _finite(b)
    if not len(va) or not len(vb):
        return NO_EFFECT
    diff = float(va.mean() - vb.mean())
    if len(va) < 2 or len(vb) < 2:
        return Effect(diff, None, None)
    sa, sb = va.var(ddof=1) / len(va), vb.var(ddof=1) / len(vb)
    if sa + sb == 0:
        return Effect(diff, None, None)
    df = (sa + sb) ** 2 / (sa ** 2 / (len(va) - 1) + sb ** 2 / (len(vb) - 1))
    half = float(stats.t.ppf(0.5 + confidence / 2, df) * math.sqrt(sa + sb))
    return Effect(diff, diff - half, diff + half)


def cliffs_delta(a: Sequence[float], b: Sequence[float], confidence: float = CONFIDENCE,
                 normal: bool = False) -> Effect:
    """Cliff's delta, P(a > b) - P(a < b) over all pairs (-1: every a below every b), with
    Cliff's asymmetric interval (Cliff 1996; Feng & Cliff 2004): the consistent variance
    estimate and a t quantile with na + nb - 2 degrees of freedom (``normal``: the normal
    quantile). Fully separated samples would give a zero variance; as R's effsize does,
    delta is then shrunk by (na nb - 1) / (na nb) for the variance, and the bound on its own
    side is +-1. No interval with fewer than 2 values a side."""
    va, vb = _finite(a), _finite(b)
    na, nb = len(va), len(vb)
    if not na or not nb:
        return NO_EFFECT
    dom = np.sign(va[:, None] - vb[None, :])
    delta = float(dom.mean())
    if na < 2 or nb < 2:
        return Effect(delta, None, None)
    d = delta * (na * nb - 1) / (na * nb) if abs(delta) == 1 else delta
    rows, cols = dom.mean(axis=1), dom.mean(axis=0)
    s_rows = float(((rows - d) ** 2).sum()) / (na - 1)
    s_cols = float(((cols - d) ** 2).sum()) / (nb - 1)
    s_pairs = float(((dom - d) ** 2).sum()) / ((na - 1) * (nb - 1))
    var = ((nb - 1) * s_rows + (na - 1) * s_cols + s_pairs) / (na * nb)
    z = float(stats.norm.ppf(0.5 + confidence / 2) if normal
              else stats.t.ppf(0.5 + confidence / 2, na + nb - 2))
    root = z * math.sqrt(var) * math.sqrt((1 - d * d) ** 2 + z * z * var)
    low, high = ((d - d ** 3 + sign * root) / (1 - d * d + z * z * var) for sign in (-1, 1))
    if delta == 1:
        high = 1.0
    if delta == -1:
        low = -1.0
    return Effect(delta, float(low), float(high))


def wilson(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson's score interval for a proportion (sound at 0/n and n/n, unlike Wald's)."""
    z = float(stats.norm.ppf(0.5 + confidence / 2))
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def proportion_difference(xa: int, na: int, xb: int, nb: int,
                          confidence: float = CONFIDENCE) -> Effect:
    """xa/na - xb/nb with Newcombe's hybrid score interval (Newcombe 1998, method 10: from
    the two Wilson intervals), which stays inside [-1, 1] and works at 0 % and 100 %."""
    if na < 1 or nb < 1:
        return NO_EFFECT
    pa, pb = xa / na, xb / nb
    la, ua = wilson(xa, na, confidence)
    lb, ub = wilson(xb, nb, confidence)
    diff = pa - pb
    return Effect(diff, diff - math.sqrt((pa - la) ** 2 + (ub - pb) ** 2),
                  diff + math.sqrt((ua - pa) ** 2 + (pb - lb) ** 2))


def mann_whitney(a: Sequence[float], b: Sequence[float]) -> tuple[float, float, bool]:
    """(U of a, two-sided p, exact): the exact test when no value repeats (its p can then
    reach min_p_mann_whitney), else the normal approximation with the tie correction."""
    va, vb = _finite(a), _finite(b)
    exact = len(np.unique(np.concatenate([va, vb]))) == len(va) + len(vb)
    result = stats.mannwhitneyu(va, vb, alternative="two-sided",
                                method="exact" if exact else "asymptotic")
    return float(result.statistic), float(result.pvalue), exact
