"""One frozen configuration object holding every learner parameter.

The paper (Nguyen, Baranes & Oudeyer, ICDL 2011) gives only a few values; every other default
is documented with where it comes from (explauto, the SGIM-lineage code base described in
shared/notes/sgim-reference-values.md) or why we chose it.  Frozen so that no component can
mutate the configuration during a run (a known defect of explauto's config dicts).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any


@dataclass(frozen=True)
class LearnerConfig:
    """All parameters of the learners.  Distances are Euclidean in outcome units ([-1, 1]^m)
    unless stated otherwise."""

    # --- competence (paper, section on SAGG-RIAC competence) ---
    eps_sim: float = -0.05
    """Sim is in [-1, 0] (0 = goal reached exactly).  A Sim above eps_sim, i.e. an error below
    5 % of the goal's distance from the origin outcome, is treated as full success
    (competence 0).  Chosen because the paper gives no value; must lie in [-1, 0]."""
    origin: tuple[float, ...] | None = None
    """y_org of the similarity: the outcome the learner starts from.  None = centre of the
    outcome space.  Chosen because the worlds start the float/hand near the centre."""

    # --- region tree (paper eq. 2) ---
    max_goals_per_region: int = 50
    """A region splits once it holds MORE than this many goals.  SGIM-lineage code: 50
    (explauto: 100); 50 gives regions quickly enough in a 5000-movement run."""
    zeta: int = 20
    """Interest window (eq. 2), even.  Between the SGIM-lineage 10 and explauto 50; must not
    exceed max_goals_per_region (explauto checks the same)."""
    min_goals_per_child: int = 5
    """A candidate cut must leave at least this many goals on each side; chosen because a
    child with almost no goals has a meaningless interest and the split would be degenerate."""
    min_region_width: float = 0.05
    """A dimension narrower than this is not cut; chosen to stop endless splitting when mode 3
    piles goals onto one point."""

    # --- goal selection (paper section on the three modes) ---
    p_mode1: float = 0.6
    """Region by interest, uniform goal in it.  SGIM-lineage code: 0.6."""
    p_mode2: float = 0.2
    """Uniform goal in the whole space.  SGIM-lineage code: 0.2."""
    p_mode3: float = 0.2
    """Region by interest, goal near its least competent goal.  SGIM-lineage code: 0.2."""
    mode3_radius: float = 0.05
    """Half-width of the box around the least competent goal in mode 3; chosen as roughly the
    paper's outcome noise (0.073) so mode 3 probes the same neighbourhood."""

    # --- inverse model (paper, alpha given) ---
    l_max: int = 10
    """Candidate nearest neighbours of the goal.  Chosen; the paper gives no value."""
    k_max: int = 5
    """Neighbours of each candidate used for its variance and the interpolation.  Chosen."""
    alpha: float = 0.5
    """Reliability = distance + alpha * variance.  Paper: 0.5."""
    interpolation_sigma: float = 0.05
    """Width of the Gaussian interpolation weights (outcome units); chosen near the paper's
    noise 0.073 so that neighbours within the noise weigh alike."""

    # --- goal reaching ---
    explore_gain: float = 2.0
    """P(explore) = min(explore_cap, explore_gain * distance to the closest reached outcome).
    Proportional as the issue states; the SGIM-lineage slope is 0.9/(0.1*2) = 4.5 per unit;
    we halve it so that goals just outside the reached set are still attempted."""
    explore_cap: float = 0.5
    """Cap on P(explore).  Chosen: with a cap of 1 goals far from the reached set would never be
    attempted, which is exactly where goal babbling extends the reached set."""
    reach_threshold: float = 0.03
    """A goal attempt stops once an outcome is this close to the goal; chosen below the paper's
    noise 0.073 so it is rarely hit by chance."""
    goal_budget: int = 10
    """Movements per goal attempt (inverse model + Nelder-Mead).  Chosen: 5000 movements then
    give >= 500 goals, enough to split the tree several times."""
    nm_initial_step: float = 0.1
    """Step of the padding vertices added when memory cannot fill the Nelder-Mead simplex."""
    failure_cost: float = 2.8284271247461903
    """Cost given to Nelder-Mead for a failed movement: the diagonal of [-1, 1]^2, i.e. worse
    than any real outcome."""

    # --- social learning (paper) ---
    imitation_count: int = 5
    """Imitations a_demo + a_rand after each demonstration.  Chosen; the paper gives none."""
    imitation_epsilon: float = 0.2
    """Bound on the Euclidean norm of a_rand (so also on each component).  Chosen small
    relative to the action range [-1, 1]."""

    # --- memory index ---
    memory_rebuild_fraction: float = 0.5
    """The KD-tree is rebuilt when the unindexed tail exceeds this fraction of the indexed
    part: geometric rebuilds, O(n log n) total upkeep."""
    memory_min_tail: int = 64
    """Tail size always tolerated before a rebuild (brute force over 64 rows is ~µs)."""
    memory_max_tail: int = 512
    """Tail size that always triggers a rebuild: bounds the brute-force part of a query
    (~40 µs at 512 rows) whatever the memory size; measured by benchmarks/bench_memory.py."""

    def __post_init__(self) -> None:
        def fail(name: str, why: str) -> None:
            raise ValueError(f"LearnerConfig.{name}: {why} (got {getattr(self, name)!r})")

        if not -1.0 <= self.eps_sim <= 0.0:
            fail("eps_sim", "must be in [-1, 0] because Sim is in [-1, 0]")
        if self.origin is not None and len(self.origin) == 0:
            fail("origin", "must be None or a non-empty tuple")
        for name in ("max_goals_per_region", "zeta", "l_max", "k_max", "goal_budget",
                     "memory_min_tail", "memory_max_tail"):
            if int(getattr(self, name)) < 1:
                fail(name, "must be >= 1")
        if self.zeta % 2:
            fail("zeta", "must be even (two equal halves in eq. 2)")
        if self.zeta > self.max_goals_per_region:
            fail("zeta", "must not exceed max_goals_per_region")
        if self.min_goals_per_child < 1:
            fail("min_goals_per_child", "must be >= 1")
        if 2 * self.min_goals_per_child > self.max_goals_per_region + 1:
            fail("min_goals_per_child", "two children must fit in a full region")
        for name in ("p_mode1", "p_mode2", "p_mode3"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                fail(name, "must be a probability in [0, 1]")
        if abs(self.p_mode1 + self.p_mode2 + self.p_mode3 - 1.0) > 1e-9:
            fail("p_mode1", "p_mode1 + p_mode2 + p_mode3 must equal 1")
        for name in ("mode3_radius", "interpolation_sigma", "reach_threshold",
                     "nm_initial_step", "failure_cost", "imitation_epsilon",
                     "memory_rebuild_fraction"):
            if not getattr(self, name) > 0.0:
                fail(name, "must be > 0")
        for name in ("alpha", "explore_gain", "min_region_width"):
            if getattr(self, name) < 0.0:
                fail(name, "must be >= 0")
        if not 0.0 <= self.explore_cap <= 1.0:
            fail("explore_cap", "must be in [0, 1]")
        if self.imitation_count < 0:
            fail("imitation_count", "must be >= 0")

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (for the run log header)."""
        return asdict(self)

    @classmethod
    def field_names(cls) -> list[str]:
        return [f.name for f in fields(cls)]
