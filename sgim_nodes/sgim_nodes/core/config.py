"""One frozen configuration object holding every learner parameter.

The paper (Nguyen, Baranes & Oudeyer, ICDL 2011) gives only a few values; every other default
is documented with where it comes from (explauto, the SGIM-lineage code base described in
shared/notes/sgim-reference-values.md) or the measurement that chose it (docs/learners.md,
``benchmarks/bench_learners.py``). Frozen so that no component can mutate the configuration
during a run (a known defect of explauto's config dicts).

Distances are never absolute: a field ending in ``_noise`` is a multiple of the world's
outcome noise, one ending in ``_size`` a multiple of the side of its outcome box (both declared
by the world, ``scale.WorldScale``); ``distances(scale)`` turns them into outcome units. The
same parameter file therefore runs the planar arms and the fishing world. Action-space values
(``*_action``) are in action units: every world's actions live in [-1, 1]^n.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, fields
from typing import Any

import numpy as np

from .competence import competence
from .region_tree import SPLIT_QUALITIES
from .scale import WorldScale

INVERSE_MODELS = ("nearest", "reliable", "local-linear")
STEP_CHECKS = ("held-out", "none")
OPTIMISERS = ("subspace", "local-linear", "nelder-mead", "random-search")
CHOICE_ORDERS = ("pair", "region-first")
STRATEGY_VALUES = ("interest", "gain")


@dataclass(frozen=True)
class Distances:
    """The configuration's distances in one world's outcome units (see LearnerConfig)."""

    success_tolerance: float
    competence_radius: float
    competence_floor: float
    reach_threshold: float
    mode3_radius: float
    min_region_width: float
    explore_distance: float
    failure_cost: float
    competence_reference: str = "memory"

    def competence(self, goal: np.ndarray, best_outcome: np.ndarray | None,
                   start_distance: float) -> float:
        """An attempt's competence at ``goal`` (competence.py), against the configured
        reference: memory's distance to the goal before the attempt (``start_distance``), or
        the fixed radius. One rule for every learner and node that measures one."""
        reference = (start_distance if self.competence_reference == "memory"
                     else self.competence_radius)
        return competence(goal, best_outcome, reference, self.success_tolerance,
                          self.competence_floor)


@dataclass(frozen=True)
class Range:
    """A field's own range: numbers from ``low`` (excluded when ``low_open``) to ``high``, or
    one of ``choices``. Declared once here; LearnerConfig checks it, and the ROS parameters
    carry it (nodes/ros_glue.py)."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] = ()

    def problem(self, value: Any) -> str:
        """Why ``value`` is out of the range, or '' (NaN is out of every numeric range)."""
        if self.choices:
            return "" if value in self.choices else f"must be one of {', '.join(self.choices)}"
        low_ok = self.low is None or (value > self.low if self.low_open else value >= self.low)
        if low_ok and (self.high is None or value <= self.high):
            return ""
        if self.high is None:
            return f"must be {'>' if self.low_open else '>='} {self.low:g}"
        if self.low is None:
            return f"must be <= {self.high:g}"
        return f"must be in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}]"


AT_LEAST_ONE, PROBABILITY, POSITIVE, NON_NEGATIVE = (
    Range(1), Range(0.0, 1.0), Range(0.0, low_open=True), Range(0.0))


@dataclass(frozen=True)
class Tie:
    """A rule on fields beyond each one's own range. LearnerConfig refuses a configuration
    that breaks it, naming the first of ``fields`` with ``refusal``; the reference page states
    ``rule`` beside the range of every field it names (nodes/ros_glue.py)."""

    fields: tuple[str, ...]
    rule: str  # as the page states it
    refusal: str  # why a configuration that breaks it is refused
    holds: Callable[[LearnerConfig], bool]


TIES = (
    Tie(("zeta",), "even", "must be even (two equal halves in eq. 2)",
        lambda c: c.zeta % 2 == 0),
    Tie(("zeta", "max_goals_per_region"), "zeta <= max_goals_per_region",
        "must not exceed max_goals_per_region", lambda c: c.zeta <= c.max_goals_per_region),
    Tie(("min_goals_per_child", "max_goals_per_region"),
        "2 * min_goals_per_child <= max_goals_per_region + 1",
        "two children must fit in a full region",
        lambda c: 2 * c.min_goals_per_child <= c.max_goals_per_region + 1),
    Tie(("p_mode1", "p_mode2", "p_mode3"), "p_mode1 + p_mode2 + p_mode3 = 1",
        "p_mode1 + p_mode2 + p_mode3 must equal 1",
        lambda c: abs(c.p_mode1 + c.p_mode2 + c.p_mode3 - 1.0) <= 1e-9),
)
"""Every rule LearnerConfig checks that a field's own range cannot say."""


@dataclass(frozen=True)
class LearnerConfig:
    """All parameters of the learners (sources in each field's docstring)."""

    # --- competence (the paper's SAGG-RIAC competence) ---
    success_tolerance_noise: float = 1.0
    """An attempt whose best outcome lands within this many noise units of its goal is a full
    success (competence 0): closer than the world's own noise, a miss is no information about
    the learner's skill. Chosen as one noise unit."""

    competence_reference: str = "memory"
    """What an attempt's distance is measured against: ``memory`` (the closest outcome memory
    held before the attempt, the paper's y_start) or ``fixed`` (competence_radius_noise noise
    units: every goal farther than that from anything reachable has the constant -1)."""
    competence_radius_noise: float = 4.0
    """The fixed reference distance of ``competence_reference: fixed``, in noise units."""
    competence_floor_noise: float = 1.0
    """Smallest reference distance of ``competence_reference: memory`` (competence.py), in
    noise units: the competence divides an attempt's miss beyond the tolerance by memory's
    distance beyond it, and where memory already lands near the goal this floor keeps a
    noise-sized miss from counting as a total failure."""

    # --- region tree (paper eq. 2) ---
    max_goals_per_region: int = 100
    """A region splits once it holds MORE than this many goals.  explauto: 100 (SGIM-lineage
    code: 50).  Chosen with ``zeta`` on the arms' validation goals (docs/learners.md, section
    5): with 50 and 20, SAGG-RIAC's interest read noise in many small leaves and it ended
    significantly behind random goals on the 20-joint arm; with explauto's pair it ties."""
    zeta: int = 50
    """Interest window (eq. 2), even.  explauto: 50 (SGIM-lineage code: 10); must not exceed
    max_goals_per_region (explauto checks the same).  Chosen with ``max_goals_per_region``
    (docs/learners.md, section 5): neither alone does what the pair does."""
    min_goals_per_child: int = 5
    """A candidate cut must leave at least this many goals on each side; chosen because a
    child with almost no goals has a meaningless interest and the split would be degenerate."""
    interest_noise_correction: float = 0.0
    """Standard errors removed from the difference of the window halves' mean competences
    before it counts as progress (region_tree.interest); 0 is the paper's eq. 2 as written,
    the default: with competence against memory, unreachable and mastered goals already have
    constant competences, and on the fishing world the paper's formula kept mode-1 goals off
    the land (docs/learners.md); 1 spread goals more evenly on the arms."""
    region_split: str = "gap"
    """How a full region chooses its cut (region_tree.split_quality): ``gap`` maximises the
    children's interest difference alone; ``balanced`` maximises card(left) * card(right) *
    sqrt(difference), a split quality that also rewards balanced children, after Baranes &
    Oudeyer's R-IAC (2009) and SAGG-RIAC (2013) as recalled, not checked against their text
    here. Default ``gap``: ``balanced`` did not lower the 20-joint arm's error
    (docs/notes/measurements.md)."""
    min_region_width_size: float = 0.025
    """A dimension narrower than this fraction of the outcome box is not cut; stops endless
    splitting when mode 3 piles goals onto one point.  Chosen: 0.05 on [-1, 1]."""

    # --- goal selection (paper section on the three modes) ---
    p_mode1: float = 0.6
    """Region by interest, uniform goal in it.  SGIM-lineage code: 0.6."""
    p_mode2: float = 0.2
    """Uniform goal in the whole space.  SGIM-lineage code: 0.2."""
    p_mode3: float = 0.2
    """Region by interest, goal near its least competent goal.  SGIM-lineage code: 0.2."""
    mode3_radius_noise: float = 1.0
    """Half-width of the box around the least competent goal in mode 3, in noise units: mode 3
    probes the neighbourhood the world's noise makes indistinguishable.  Chosen."""

    # --- inverse model ---
    inverse_model: str = "local-linear"
    """How a goal becomes an action (docs/learners.md measures the three): ``nearest`` (the
    action of the stored outcome nearest to the goal), ``reliable`` (the paper's reliability
    rank among l_max candidates, the best candidate's own action, never an average of several
    neighbourhoods), ``local-linear`` (that action moved by one step of a linear model fitted
    in its own action neighbourhood)."""
    l_max: int = 10
    """Candidate nearest neighbours of the goal.  Chosen; the paper gives no value."""
    k_max: int = 5
    """Outcome neighbours of each candidate whose actions give its variance.  Chosen."""
    alpha: float = 0.5
    """Reliability = distance + alpha * variance.  Paper: 0.5."""
    local_radius_action: float = 0.2
    """Radius of the action neighbourhood a local linear model is fitted on, in action units per
    number (times sqrt(action size) as a Euclidean radius).  Chosen by measurement."""
    local_neighbours: int = 60
    """At most this many pairs (the nearest in action space within the radius) per fit."""
    local_step_fraction: float = 0.25
    """The local-linear inverse moves the chosen action towards the goal by at most this
    fraction of the fit's radius.  Chosen by measurement (docs/learners.md)."""
    local_step_support: float = 0.0
    """When > 0, the local-linear inverse's step also goes no farther than this many times the
    fit's spread of actions along the step's direction (its weighted rms offset that way): past
    the casts it was fitted on, a linear model extrapolates. Measured and not kept (0, no such
    bound): on final memories 2 turned the one fishing loss to the nearest neighbour into a
    gain and kept the arms' gains, but learning with it, SAGG-RIAC on fishing, 10 seeds, ended
    farther from the validation goals (0.106 against 0.093, paired p = 0.02;
    docs/learners.md, section 1)."""
    local_min_casts: float = 10.0
    """The local-linear inverse takes its step only when the fit averages at least this many
    casts (its effective number of pairs, local_model.LocalFit.n_effective); below, it returns
    the chosen pair's own action. A linear model of 24 action numbers fitted on a handful of
    casts is fitted to their noise: on a sparse fishing memory such steps made the inverse
    model worse than the nearest neighbour (docs/learners.md, section 1). 10 keeps the whole
    benefit of the step on the arms' validation goals (25 lost part of it). Chosen."""
    local_rank_min_casts: float = 5.0
    """The local-linear inverse ranks a candidate by its fit's prediction only when that fit
    averages at least this many casts; a candidate with a thinner fit is ranked by its own
    stored outcome, as the nearest neighbour ranks it. A prediction from a handful of casts
    carries their noise and the curvature between them: on the arms' random motor babbling
    memories, where fits are thin, ranking by it lost to the nearest neighbour in half of the
    runs by up to 0.0005, and with 5 it gives the nearest neighbour's answer there; 3 still
    lost once in 10, 10 gave up part of the ranking's gain on SAGG-RIAC's 20-joint memories
    (docs/learners.md, section 1). Chosen by measurement on the arms' validation goals."""
    local_step_check: str = "held-out"
    """``held-out``: the local-linear inverse takes its step only when the gain it predicts
    exceeds the fit's leave-one-out error beyond the world's noise (inverse_model.py); a
    model-selection test by cross-validation, as in locally weighted learning (Atkeson, Moore
    and Schaal 1997). ``none``: whenever the fit is large enough. Chosen by measurement
    (docs/learners.md, section 1): as good as ``none`` on the arms' validation goals, and on
    the fishing memories where the step had lost to the nearest neighbour it stays out."""

    # --- goal reaching ---
    explore_gain: float = 4.0
    """P(explore) = min(explore_cap, explore_gain * d / box side), d the distance from the goal
    to the closest reached outcome: the paper's rule (it grows with d).  SGIM-lineage code:
    0.9 / 0.1 = 9 per box side above a 0.1 floor; chosen by measurement (docs/learners.md)."""
    explore_cap: float = 0.5
    """Cap on P(explore): goals far from the reached set are still attempted half of the time,
    since that is where goal babbling extends the reached set.  Chosen."""
    explore_action: float = 0.3
    """Exploring perturbs the best-known action for the goal with Gaussian noise of standard
    deviation min(explore_action, explore_action * d / explore_distance) per action number:
    small near what is known, up to explore_action far from it.  Chosen by measurement."""
    explore_distance_size: float = 0.25
    """Distance (fraction of the box side) at which exploration reaches its full width."""
    reach_threshold_noise: float = 0.5
    """A goal attempt stops once an outcome lands within this many noise units of the goal: a
    closer landing is luck, more movements cannot do better on average.  Chosen."""
    attempt_patience: int = 1
    """A goal attempt gives up after this many movements in a row without a new best: an
    unreachable goal (or one memory already reaches within the noise) then costs two
    movements, not the whole budget.  Chosen by measurement on the arms' validation goals
    (docs/learners.md): 1 gave the lowest errors; the budget still caps attempts that keep
    gaining."""
    goal_budget: int = 10
    """Movements per goal attempt (inverse model + refinement).  Chosen: 5000 movements then
    give >= 500 goals, enough to split the tree several times."""
    optimiser: str = "local-linear"
    """The refinement on real movements: ``local-linear`` (trust-region steps of a linear model
    refitted after every movement), ``nelder-mead`` (ask/tell simplex seeded from memory),
    ``random-search`` ((1+1) evolution strategy).  Chosen by measurement (docs/learners.md)."""
    trust_radius_action: float = 0.1
    """Initial trust radius of the local-linear refinement and step of the random search, in
    action units per number (times sqrt(action size) as a Euclidean radius).  Chosen."""
    nm_initial_step: float = 0.1
    """Step of the padding vertices added when memory cannot fill the Nelder-Mead simplex."""
    failure_cost_size: float = 1.5
    """Cost told to the optimiser for a failed movement, in box sides: worse than any real
    outcome (the box diagonal of a square is 1.41 sides)."""

    # --- social learning (paper) ---
    imitation_count: int = 5
    """Imitations a_demo + a_rand after each demonstration.  Chosen; the paper gives none."""
    imitation_epsilon: float = 0.05
    """Bound on the Euclidean norm of a_rand (so also on each component), in action units.
    Chosen by measurement on the fishing world's teaching set: the width at which most
    imitations still land within the world's noise of the demonstrated outcome, while a wider
    one scatters them (docs/notes/measurements.md, "how far imitations land")."""

    # --- SGIM-ACTS: each kind of strategy's cost (strategies.py) and the choice ---
    acts_cost_autonomous: float = 1.0
    """Cost of one autonomous episode (SAGG-RIAC's goal attempt), in movement-equivalents:
    the unit. SGIM-ACTS (Nguyen & Oudeyer 2012) divides each (strategy, region) pair's
    competence progress by its strategy's cost; only SGIM-ACTS reads these three fields."""
    acts_cost_emulation: float = 5.0
    """Cost of asking a teacher for an outcome to reach (emulation). The 2012 paper makes the
    social strategies dearer than autonomous exploration; its values were not at hand, so this
    one is chosen: a request takes a person's attention and one demonstration of theirs,
    scarcer than the robot's own movements (the paper's SGIM-D teacher speaks once every 150
    movements), and showing only where the result should land asks the least of the teacher.
    Chosen, not measured."""
    acts_cost_mimicry: float = 10.0
    """Cost of asking a teacher for its movement itself (mimicry): the teacher must show the
    whole action in a form the learner can copy (kinesthetic or teleoperated), about twice the
    effort of showing an effect (emulation). Chosen, not measured. A cost weighs the
    strategy's interest and is tallied per request; it spends no movements of the budget."""
    strategy_choice_order: str = "pair"
    """How SGIM-ACTS chooses an episode's region and strategy (strategy_choice.py): ``pair``
    draws a (region, strategy) pair at once by value / cost (eq. 3 over the pairs; mode 2
    draws the strategy uniformly), the SGIM lineage's choice and the default; ``region-first``
    chooses the goal as SAGG-RIAC does in all three modes (its region by the region's own
    interest), then, in that region, the strategy of largest value / cost, ties drawn at
    random: what to learn, then how and from whom, so that no mode draws a teacher blindly.
    A variant to compare, chosen, not measured."""
    strategy_value: str = "interest"
    """What a (strategy, region) pair is worth before its cost divides it: ``interest``, eq.
    2's competence progress on the pair's history (the SGIM lineage's, the default), or
    ``gain``, the mean of 1 + competence over the pair's last zeta episodes: how near its
    goals the strategy brings the learner. A teacher whose help is steadily good keeps a
    high gain, while its interest, a change of competence, falls to zero once that help is
    steady. An untried pair is worth the largest gain, 1, so that a teacher is tried where
    the learner's own gain is low. A variant to compare, chosen, not measured."""

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

        for name, bound in RANGES.items():  # each field within its own range first
            problem = bound.problem(getattr(self, name))
            if problem:
                fail(name, problem)
        for tie in TIES:
            if not tie.holds(self):
                fail(tie.fields[0], tie.refusal)

    def distances(self, scale: WorldScale) -> Distances:
        """This configuration's distances in the outcome units of the world ``scale``."""
        return Distances(
            success_tolerance=self.success_tolerance_noise * scale.noise,
            competence_radius=self.competence_radius_noise * scale.noise,
            competence_floor=self.competence_floor_noise * scale.noise,
            reach_threshold=self.reach_threshold_noise * scale.noise,
            mode3_radius=self.mode3_radius_noise * scale.noise,
            min_region_width=self.min_region_width_size * scale.size,
            explore_distance=self.explore_distance_size * scale.size,
            failure_cost=self.failure_cost_size * scale.size,
            competence_reference=self.competence_reference,
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (for the run log header)."""
        return asdict(self)

    @classmethod
    def field_names(cls) -> list[str]:
        return [f.name for f in fields(cls)]


RANGES: dict[str, Range] = {
    **dict.fromkeys(("max_goals_per_region", "zeta", "l_max", "k_max", "goal_budget",
                     "attempt_patience", "memory_min_tail", "memory_max_tail",
                     "local_neighbours", "min_goals_per_child"), AT_LEAST_ONE),
    **dict.fromkeys(("p_mode1", "p_mode2", "p_mode3", "explore_cap"), PROBABILITY),
    **dict.fromkeys(("mode3_radius_noise", "reach_threshold_noise", "nm_initial_step",
                     "local_radius_action", "local_step_fraction", "failure_cost_size",
                     "imitation_epsilon", "memory_rebuild_fraction", "explore_distance_size",
                     "trust_radius_action", "competence_radius_noise",
                     "competence_floor_noise", "acts_cost_autonomous", "acts_cost_emulation",
                     "acts_cost_mimicry"), POSITIVE),
    **dict.fromkeys(("alpha", "explore_gain", "min_region_width_size", "explore_action",
                     "success_tolerance_noise", "interest_noise_correction",
                     "imitation_count", "local_min_casts",
                     "local_rank_min_casts", "local_step_support"), NON_NEGATIVE),
    "inverse_model": Range(choices=INVERSE_MODELS),
    "local_step_check": Range(choices=STEP_CHECKS),
    "optimiser": Range(choices=OPTIMISERS),
    "competence_reference": Range(choices=("memory", "fixed")),
    "region_split": Range(choices=SPLIT_QUALITIES),
    "strategy_choice_order": Range(choices=CHOICE_ORDERS),
    "strategy_value": Range(choices=STRATEGY_VALUES),
}
"""The range of every LearnerConfig field, declared once (the rules that tie fields together
are TIES)."""


BEFORE_IT_EXISTED: dict[str, Any] = {"local_step_check": "none", "local_rank_min_casts": 0.0,
                                     "local_step_support": 0.0,
                                     "strategy_choice_order": "pair",
                                     "strategy_value": "interest"}
"""For a field added after runs were recorded: the value that does what the learner did before
the field existed. A run recorded then, resumed today, goes on as it ran (recorded_learner)."""


def recorded_learner(recorded: dict[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """What a run's recorded parameters (every LearnerConfig field, as run_experiment writes
    them) leave out: the fields whose earlier behaviour BEFORE_IT_EXISTED knows, with those
    values, and the names of the others (they take today's defaults)."""
    absent = [name for name in LearnerConfig.field_names() if name not in recorded]
    known = {name: BEFORE_IT_EXISTED[name] for name in absent if name in BEFORE_IT_EXISTED}
    return known, [name for name in absent if name not in known]
