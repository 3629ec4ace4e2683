"""What the fuzz tests tried and what became of each case, for the session's summary.

Each fuzz test counts its cases by target and outcome (accepted, refused, quarantined, ...);
conftest.py prints the table at the end of the session, so a note or a CI log can give the
numbers. Hypothesis settings live here too: few enough cases to stay within tens of seconds on
2 shared cores, no deadline (a loaded machine is not a bug), no example database written into
the tree, and the same cases every run unless SGIM_FUZZ_RANDOM=1 (then a new draw each run);
SGIM_FUZZ_SCALE multiplies every test's number of cases.
"""

from __future__ import annotations

import os
from collections import Counter, defaultdict

from hypothesis import HealthCheck, settings

COUNTS: dict[str, Counter[str]] = defaultdict(Counter)
SCALE = float(os.environ.get("SGIM_FUZZ_SCALE", "1"))


def tally(target: str, outcome: str) -> None:
    """Count one case of `target` that ended as `outcome`."""
    COUNTS[target][outcome] += 1


def fuzz(examples: int) -> settings:
    """The Hypothesis settings of a fuzz test trying `examples` cases (times SGIM_FUZZ_SCALE)."""
    return settings(max_examples=max(1, int(examples * SCALE)), deadline=None, database=None,
                    derandomize=os.environ.get("SGIM_FUZZ_RANDOM") != "1",
                    suppress_health_check=[HealthCheck.too_slow,
                                           HealthCheck.function_scoped_fixture,
                                           HealthCheck.filter_too_much,
                                           HealthCheck.data_too_large])


def summary() -> list[str]:
    """One line per target: cases tried and each outcome's count."""
    lines = []
    for target in sorted(COUNTS):
        counts = COUNTS[target]
        parts = ", ".join(f"{outcome} {n}" for outcome, n in sorted(counts.items()))
        lines.append(f"{target}: {sum(counts.values())} cases ({parts})")
    return lines
