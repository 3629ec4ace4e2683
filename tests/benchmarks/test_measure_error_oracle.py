"""measure_error_oracle.py: before its movement the learner keeps its own goals; after it,
goals fall in reached cells only, more often where the learner errs more."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from tests.conftest import PYTHON, REPO

sys.path.insert(0, str(REPO / "benchmarks"))


def small_reach():
    """A 4 x 4 map of the unit box [-1, 1]^2 with two reached cells: one next to the point an
    empty memory's action lands on (the stretched arm, (1, 0)), one far from it."""
    from learner_probes import ReachMap

    reached = np.zeros((4, 4), bool)
    reached[3, 1] = True   # x in [0.5, 1), y in [-0.5, 0): centre (0.75, -0.25), error 0.35
    reached[0, 3] = True   # x in [-1, -0.5), y in [0.5, 1): centre (-0.75, 0.75), error 1.9
    return ReachMap(np.array([-1.0, -1.0]), np.array([1.0, 1.0]), reached)


def learner_and_arm():
    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.core.learners import make_learner
    from sgim_nodes.core.planar_arm import PlanarArm

    arm = PlanarArm(n_joints=3)
    return make_learner("random-goals", 3, 2, 0, LearnerConfig(), arm.scale), arm


def test_goals_are_the_learners_own_before_and_error_weighted_after():
    from measure_error_oracle import ErrorOracle

    learner, arm = learner_and_arm()
    reach = small_reach()
    oracle = ErrorOracle(learner, arm.forward, reach, after=50, every=10, power=1.0)
    rng = np.random.default_rng(0)
    early = np.array([learner.selector.sample(rng).goal for _ in range(300)])
    assert reach.share(early) > 0.7  # uniform in the box: mostly outside the two cells
    assert oracle.errors == []
    learner.n_movements = 50
    late = np.array([learner.selector.sample(rng).goal for _ in range(2000)])
    assert reach.share(late) == 0.0
    far = np.mean((late[:, 0] < -0.5) & (late[:, 1] > 0.5))
    # probabilities proportional to the errors at the centres: 1.90 / (1.90 + 0.35) = 0.84
    assert 0.80 < far < 0.88
    assert len(oracle.errors) == 1  # measured once: no movement happened since


def test_power_zero_is_uniform_over_reached_cells():
    from measure_error_oracle import ErrorOracle

    learner, arm = learner_and_arm()
    ErrorOracle(learner, arm.forward, small_reach(), after=0, every=10, power=0.0)
    rng = np.random.default_rng(1)
    late = np.array([learner.selector.sample(rng).goal for _ in range(2000)])
    far = np.mean((late[:, 0] < -0.5) & (late[:, 1] > 0.5))
    assert 0.45 < far < 0.55


def test_bad_options_are_refused():
    script = str(REPO / "benchmarks" / "measure_error_oracle.py")
    for args, word in ((["--after", "5000"], "--after"), (["--power", "-1"], "--power"),
                       (["--every", "0"], "--every"), (["--first-seed", "-1"], "--first-seed")):
        done = subprocess.run([PYTHON, script, *args], capture_output=True, text=True,
                              timeout=120)
        assert done.returncode == 2 and word in done.stderr, (args, done.stderr)


def test_the_paired_comparison_matches_runs_by_seed():
    from measure_error_oracle import ORACLE, UNIFORM, paired

    rows = {UNIFORM: [{"seed": s, "final": v} for s, v in ((0, 0.040), (1, 0.050), (2, 0.030))],
            ORACLE: [{"seed": s, "final": v} for s, v in ((2, 0.031), (0, 0.037), (1, 0.046))]}
    text = paired(rows)
    assert "-0.0020" in text and "better in 2/3" in text
