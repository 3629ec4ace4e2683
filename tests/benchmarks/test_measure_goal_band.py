"""measure_goal_band.py: its band holds reachable space and grows with the margin, and its
restricted learner's goals stay inside it."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from tests.conftest import PYTHON, REPO

sys.path.insert(0, str(REPO / "benchmarks"))


@pytest.fixture(scope="module")
def reach():
    """arm-20's reach map, made once for the module (a least-squares flood of its grid)."""
    import bench_learners as bl

    return bl.reach_map("arm-20")


def test_the_band_holds_reachable_space_and_grows_with_the_margin(reach):
    from measure_goal_band import UNRESTRICTED, band

    narrow, wide = band(reach, 0.05), band(reach, 0.3)
    assert np.all(narrow.reached[reach.reached]) and np.all(wide.reached[narrow.reached])
    assert reach.area_share > narrow.area_share > wide.area_share > 0.0
    assert band(reach, UNRESTRICTED).area_share == 0.0


def test_restricted_goals_stay_in_the_band(reach):
    import bench_learners as bl
    from measure_goal_band import band

    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.core.learners import make_learner
    from sgim_nodes.core.planar_arm import ARMS

    allowed = band(reach, 0.05)
    arm = ARMS["arm-20"].make(0)  # its dimensions and scale (no benchmark or teaching set)
    learner = make_learner("random-goals", arm.action_dim, arm.outcome_dim, 0,
                           LearnerConfig(), arm.scale)
    bl.restrict_to_reachable(learner, allowed)
    rng = np.random.default_rng(1)
    goals = np.array([learner.selector.sample(rng).goal for _ in range(200)])
    assert allowed.share(goals) == 0.0


def test_the_restriction_starts_at_its_movement(reach):
    """--after: goals are the learner's own (uniform) before the movement, in the band after."""
    import bench_learners as bl
    from measure_goal_band import band

    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.core.learners import make_learner
    from sgim_nodes.core.planar_arm import ARMS

    allowed = band(reach, 0.05)
    arm = ARMS["arm-20"].make(0)
    learner = make_learner("random-goals", arm.action_dim, arm.outcome_dim, 0,
                           LearnerConfig(), arm.scale)
    bl.restrict_to_reachable(learner, allowed, from_movement=100)
    rng = np.random.default_rng(2)
    early = np.array([learner.selector.sample(rng).goal for _ in range(400)])
    learner.n_movements = 100
    late = np.array([learner.selector.sample(rng).goal for _ in range(200)])
    assert allowed.share(early) > 0.5 * allowed.area_share
    assert allowed.share(late) == 0.0


def test_bad_margins_are_refused():
    done = subprocess.run([PYTHON, str(REPO / "benchmarks" / "measure_goal_band.py"),
                           "--margins", "0"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "margin" in done.stderr
    late = subprocess.run([PYTHON, str(REPO / "benchmarks" / "measure_goal_band.py"),
                           "--movements", "100", "--after", "100"], capture_output=True,
                          text=True, timeout=120)
    assert late.returncode == 2 and "--after" in late.stderr
