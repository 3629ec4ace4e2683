"""The second finding's pinned predictions (reports/second_finding.py) judged as written: on the
page's corrected tests, whichever side a test puts SGIM-D, and on the new seeds alone."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from sgim_nodes.analysis.statistics import compare_groups
from sgim_nodes.experiments.reports import second_finding

RNG = np.random.default_rng(0)


def runs(mean: float, n: int = 20) -> list[float]:
    return list(mean + RNG.normal(0, 0.002, n))


def corrected(pairs: dict[str, tuple[list[float], list[float]]], flip: bool = False):
    """SGIM-D against demonstrations only per group label, one corrected table."""
    groups, order = {}, []
    for label, (sgim, demo) in pairs.items():
        a, b = f"sgim-d{label}", f"demo-only{label}"
        groups[a], groups[b] = sgim, demo
        order.append((b, a) if flip else (a, b))
    return {t.a if "sgim" in t.a else t.b: t for t in compare_groups(groups, order)}


def test_the_predictions_that_held_and_the_ones_that_failed():
    made = corrected({"": (runs(0.058), runs(0.052))})
    groups = corrected({" (far)": (runs(0.064), runs(0.080)), " (near)": (runs(0.055), runs(0.041)),
                    " (pond)": (runs(0.07), runs(0.07))}, flip=True)  # SGIM-D second
    by_group = {g: groups[f"sgim-d ({g})"] for g in ("far", "near", "pond")}
    judged = second_finding.judge(made["sgim-d"], by_group,
                                  {"all": 0.005, "far": -0.01, "near": 0.012})
    assert [v.goal[:2] for v in judged] == ["S1", "S2", "S3", "S4", "S5"]
    assert [v.met for v in judged] == [True, True, True, True, True]
    assert "difference SGIM-D minus demonstrations only 0.006" in judged[0].measured
    assert "difference SGIM-D minus demonstrations only -0.016" in judged[1].measured

    closer = corrected({"": (runs(0.040), runs(0.052))})  # the paper's finding after all
    other = second_finding.judge(closer["sgim-d"], {}, {"all": -0.01, "far": -0.01,
                                                        "near": 0.01})
    assert [(v.goal[:2], v.met) for v in other] == [("S1", False), ("S5", False)]


def test_the_new_seeds_alone_are_the_seeds_added():
    groups = SimpleNamespace(
        values={"all": {"sgim-d": [0.0] * 10 + [2.0] * 10, "demo-only": [1.0] * 20},
                "far": {"sgim-d": [5.0] * 20, "demo-only": [7.0] * 20},
                "near": {"sgim-d": [1.0] * 20, "demo-only": []}},
        seeds={"sgim-d": list(range(20)), "demo-only": list(range(20))})
    assert second_finding.new_seed_differences(groups) == {"all": 1.0, "far": -2.0,
                                                           "near": None}
