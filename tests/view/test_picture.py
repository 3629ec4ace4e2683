"""The live picture every viewer draws: landings, teaching goals by the teacher's rule."""

from __future__ import annotations

import numpy as np

from sgim_nodes.core.environment import PROCESS_CODES
from sgim_nodes.core.teaching import Teacher
from sgim_nodes.view.picture import (
    INTEREST_STOPS,
    DemonstrationSeen,
    Leaf,
    LivePicture,
    interest_colour,
)

OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5]])


def picture() -> LivePicture:
    return LivePicture(Teacher(np.zeros((3, 4)), OUTCOMES, np.random.default_rng(0)))


def test_landings_failures_goal_and_imitations():
    pic = picture()
    pic.add_demonstration(DemonstrationSeen(1, 0, (0.5, 0.5), 1, "web"))
    pic.add_movement(1, 0, True, [0.1, 0.2], [0.1, 0.25])
    pic.add_movement(2, 1, False, [], [])
    pic.add_movement(3, 2, True, [0.49, 0.5], [0.5, 0.5])
    assert (pic.xs, pic.ys, pic.processes, pic.indices) == ([0.1, 0.49], [0.2, 0.5], [0, 2],
                                                            [1, 3])
    assert pic.failed == 1 and pic.count == 3 and pic.goal == (0.5, 0.5)
    assert pic.demonstrations[0].imitated_from == 3


def test_a_means_only_demonstration_is_kept_and_matched_to_its_goal_free_imitation():
    pic = picture()
    pic.add_demonstration(DemonstrationSeen(1, 0, (), -1, "automatic", content="means-only"))
    pic.add_demonstration(DemonstrationSeen(2, 0, (), -1, "automatic"))  # nothing to show
    assert [d.index for d in pic.demonstrations] == [1]
    pic.add_movement(1, 0, True, [0.1, 0.2], [0.1, 0.25])  # a goal attempt: not an imitation
    pic.add_movement(2, PROCESS_CODES["imitation"], True, [0.3, 0.3], [])
    pic.add_movement(3, PROCESS_CODES["imitation"], True, [0.3, 0.31], [])
    assert pic.demonstrations[0].imitated_from == 2
    assert pic.goal == (0.1, 0.25)  # an imitation without a goal leaves the goal as it was


def test_teaching_goals_are_judged_by_the_teachers_rule_only_when_landings_change():
    pic = picture()
    assert pic.reached.tolist() == [False, False, False]
    pic.add_movement(1, 0, True, [0.52, 0.5], [])
    assert pic.judge_teaching_goals() and pic.reached.tolist() == [False, True, False]
    version = pic.teaching_version
    assert not pic.judge_teaching_goals() and pic.teaching_version == version
    assert pic.unreached() == list(pic.teacher.unreached(pic.reached_outcomes()))


def test_interest_colours_and_budget():
    assert interest_colour(0.0) == INTEREST_STOPS[0][1]
    assert interest_colour(1.0) == interest_colour(7.0) == INTEREST_STOPS[-1][1]
    assert interest_colour(float("nan")) == INTEREST_STOPS[0][1]
    pic = picture()
    pic.set_regions([Leaf((-1, -1), (0, 1), 0.2), Leaf((0, -1), (1, 1), 0.5)])
    assert pic.highest_interest() == 0.5 and pic.regions_version == 1
    pic.set_status("sgim-d", 10, 10, "running", "")
    assert pic.budget_spent and not pic.over
