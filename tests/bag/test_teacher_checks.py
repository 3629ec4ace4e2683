"""The teacher's checks in a bag (issue 31): validated like every record, read back, and every
turn redone from them alone."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sgim_nodes.bag.reader import load_run
from sgim_nodes.bag.record_checks import Limits, check
from sgim_nodes.bag.teacher_audit import IncompleteTurn, redo, turns
from tests.bag import samples

LIMITS = Limits(action_size=24, outcome_size=2, budget=60,
                teaching_set_size=samples.TEACHING_ENTRIES)


def _check(**changes):
    """A valid check of the synthetic run's turn (entry 3, reached), with `changes`."""
    message = samples.teacher_checks(29, 1, [0.2, 0.1], 5, np.random.default_rng(0))[3]
    return dataclasses.replace(message, **changes)


def kind(record, limits=LIMITS):
    problem = check("teacher_checks", record, limits)
    return None if problem is None else problem.kind


def test_a_valid_check_passes_and_an_own_movements_one_too():
    assert kind(_check()) is None
    assert kind(_check(), Limits()) is None  # sizes known, budget and set unknown
    own = _check(rule="own-movements", action=np.zeros(0), own_outcomes=12)
    assert kind(own) is None
    nothing = _check(landed=np.zeros(0), distance=np.inf, reached=False, status=1)
    assert kind(nothing) is None  # a cast that never came down: infinitely far, unreached


@pytest.mark.parametrize("changes, expected", [
    ({"rule": "lucky"}, "bad-value"),
    ({"choice": "best-guess"}, "bad-value"),
    ({"teaching_set_index": samples.TEACHING_ENTRIES}, "unknown-teaching-index"),
    ({"teaching_set_index": -1}, "unknown-teaching-index"),
    ({"movement_index": 60}, "beyond-budget"),  # a turn comes before a movement
    ({"help_request": 0}, "bad-value"),  # an asked goal at a periodic turn
    ({"asked_goal": np.zeros(0)}, "bad-value"),  # an answer without the goal asked about
    ({"goal": np.array([0.1, np.nan])}, "non-finite"),
    ({"goal": np.array([0.1, 1.5])}, "out-of-bounds"),
    ({"action": np.zeros(3)}, "size"),
    ({"action": np.zeros(0)}, "size"),  # the ability rule's check names the model's action
    ({"rule": "own-movements"}, "size"),  # ... and an own-movements one none
    ({"landed": np.array([np.inf, 0.0])}, "non-finite"),
    ({"status": 9}, "bad-value"),
    ({"tolerance": -0.1}, "bad-value"),
    ({"distance": 0.02}, "bad-value"),  # not the distance from the goal to where it landed
    ({"distance": np.inf}, "bad-value"),
    ({"landed": np.zeros(0)}, "bad-value"),  # status OK, yet nothing landed
    ({"reached": False}, "bad-value"),  # the verdict its distance and tolerance refute
    ({"chosen": True}, "bad-value"),  # a reached entry is never shown
])
def test_an_inconsistent_check_is_quarantined_with_its_reason(changes, expected):
    assert kind(_check(**changes)) == expected


def test_a_bag_s_checks_are_read_back_and_redo_its_turn(tmp_path):
    messages = samples.synthetic_run(60)
    bag = samples.write_bag(tmp_path / "run", messages)
    run = load_run(bag, limits=LIMITS)
    assert len(run.teacher_checks) == samples.TEACHING_ENTRIES and not run.quarantined
    first = run.teacher_checks[0]
    assert (first.movement_index, first.help_request, first.rule) == (29, 1, "ability")
    assert first.action.shape == (24,) and first.landed.shape == (2,)
    (turn,) = redo(run.teacher_checks)
    (demo,) = run.demonstrations
    assert turn.verdicts_hold and (turn.movement_index, turn.help_request) == (
        demo.movement_index, demo.help_request)
    assert turn.eligible.tolist() == [demo.teaching_set_index] == list(turn.marked)
    assert turn.drawn is None  # no seed given: the draw is not replayed
    assert redo(run.teacher_checks, seed=3)[0].drawn == demo.teaching_set_index


def test_a_turn_that_lost_a_check_or_has_one_twice_is_refused():
    from sgim_nodes.bag.records import TeacherCheckRecord, to_record

    records = [to_record(TeacherCheckRecord, 0, m) for topic, m in samples.synthetic_run(60)
               if topic == "teacher_checks"]
    assert len(turns(records)) == 1
    with pytest.raises(IncompleteTurn, match="movement 29"):
        turns(records[1:])
    with pytest.raises(IncompleteTurn, match="movement 29"):
        turns([*records, records[2]])
