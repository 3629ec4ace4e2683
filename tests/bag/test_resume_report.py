"""What a resumed run takes again, from its records alone (bag/resume.py): a teacher's word
recorded but not taken where the run stopped, an answered ask not taken, an interrupted goal."""

from __future__ import annotations

import numpy as np

from sgim_nodes.bag.records import (
    CompetenceRecord,
    DemonstrationRecord,
    GoalRecord,
    MovementRecord,
    RunRecords,
)
from sgim_nodes.bag.resume import cut_imitation, finished_asks, finished_turns, what_is_redone


def demo(k: int, index: int, shown: bool = True, ask: int = 0) -> DemonstrationRecord:
    return DemonstrationRecord(0, 0, index, k, np.zeros(24) if shown else np.zeros(0),
                               np.zeros(2) if shown else np.zeros(0), 3 if shown else -1,
                               "automatic", help_request=ask)


def moves(first: int, last: int, goal: int) -> list[MovementRecord]:
    return [MovementRecord(0, 0, k, 0, 0, np.zeros(24), np.zeros(2), np.zeros(2), goal)
            for k in range(first, last + 1)]


def test_a_word_given_where_the_run_stopped_and_not_taken_is_a_turn_to_come():
    records = RunRecords(demonstrations=[demo(0, 1), demo(50, 2), demo(100, 3)],
                         demonstrations_taken=[demo(0, 1), demo(50, 2)],
                         topics={"demonstrations_taken"})
    assert finished_turns(records, 100) == {0, 50}  # the word at 100: given, not taken
    lines = what_is_redone(records, 100)
    assert lines == ["the teacher's turn at movement 100: demonstration 3 (teaching entry 3) "
                     "was given, but the learner did not take it: the turn is taken again"]
    # a word the arbiter went on from (refused, or nothing to show) is a turn done
    silent = RunRecords(demonstrations=[demo(0, 1), demo(50, 0, shown=False)],
                        demonstrations_taken=[demo(0, 1)], topics={"demonstrations_taken"})
    assert finished_turns(silent, 80) == {0, 50} and what_is_redone(silent, 80) == []
    assert finished_turns(silent, 50) == {0}
    assert "nothing to show" in what_is_redone(silent, 50)[0]


def test_an_answer_not_taken_is_asked_again():
    records = RunRecords(demonstrations=[demo(30, 1, ask=1), demo(61, 2, ask=2)],
                         demonstrations_taken=[demo(30, 1, ask=1)],
                         topics={"demonstrations_taken"})
    assert finished_asks(records, 61) == {1}
    assert what_is_redone(records, 61) == [
        "help request 2 at movement 61 was answered but the answer was not taken: the "
        "learner asks again"]


def test_an_interrupted_goal_is_named_as_dropped():
    goals = [GoalRecord(0, 0, g, 0, np.zeros(2), 0, 1) for g in (1, 2, 3)]
    competences = [CompetenceRecord(0, 0, 1, 4, np.zeros(2), np.zeros(2), -0.5, 4, False)]
    records = RunRecords(movements=moves(1, 4, 1) + moves(5, 7, 2), goals=goals,
                         competences=competences)
    assert what_is_redone(records, 7) == [
        "goal 2 was interrupted after its movements 5-7: they stay in memory, but its "
        "competence was never recorded, so the interest tree does not hold that attempt "
        "(dropped)",
        "goal 3 was drawn but the run stopped before its first movement: dropped"]


def imitations(first: int, last: int) -> list[MovementRecord]:
    return [MovementRecord(0, 0, k, 2, 0, np.zeros(24), np.array([0.1 * (k - first), 0.0]),
                           np.zeros(2), 0) for k in range(first, last + 1)]


def test_an_imitation_cut_by_the_runs_end_is_finished_and_named():
    """A kill at the 2nd of a turn's 5 imitations: the resumed run owes 3 more and the
    demonstration's competence, and the report says so."""
    records = RunRecords(movements=moves(1, 100, 1) + imitations(101, 102),
                         demonstrations=[demo(100, 1)], demonstrations_taken=[demo(100, 1)],
                         topics={"demonstrations_taken"})
    cut = cut_imitation(records, 102, 5, 300)
    assert cut is not None and (len(cut.made), cut.owed, cut.remaining) == (2, 5, 3)
    assert cut.measured and np.allclose(cut.best_outcome(), [0.0, 0.0])  # nearest (0, 0)
    assert what_is_redone(records, 102, 5, 300)[0] == (
        "the imitation of demonstration 1 (taken at movement 100) was cut after 2 of 5 "
        "movements: its 3 other imitation(s) are made and its competence recorded before the "
        "learner goes on")
    # at the budget's end it owes only the movements left
    assert cut_imitation(records, 102, 5, 103).remaining == 1
    # all made, but the competence lost: nothing to imitate, the competence to record
    whole = RunRecords(movements=moves(1, 100, 1) + imitations(101, 105),
                       demonstrations_taken=[demo(100, 1)], topics={"demonstrations_taken"})
    last = cut_imitation(whole, 105, 5, 300)
    assert last is not None and last.remaining == 0 and not last.competence_recorded
    whole.competences.append(CompetenceRecord(0, 0, 0, 105, np.zeros(2), np.zeros(2), -0.2, 5,
                                              True))
    assert cut_imitation(whole, 105, 5, 300) is None
    # the run went on after its imitation: nothing was cut
    went_on = RunRecords(movements=moves(1, 100, 1) + imitations(101, 103) + moves(104, 104, 2),
                         demonstrations_taken=[demo(100, 1)], topics={"demonstrations_taken"})
    assert cut_imitation(went_on, 104, 5, 300) is None
    # a means-only demonstration is imitated again, with no competence to record
    means = DemonstrationRecord(0, 0, 1, 100, np.zeros(24), np.zeros(0), 3, "automatic",
                                content="means-only")
    blind = RunRecords(movements=moves(1, 100, 1) + imitations(101, 101),
                       demonstrations_taken=[means], topics={"demonstrations_taken"})
    cut = cut_imitation(blind, 101, 5, 300)
    assert cut.remaining == 4 and not cut.measured
    assert "its competence" not in cut.describe()
