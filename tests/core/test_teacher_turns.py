"""Several teachers taking SGIM-D's turns (issue 33's comparison): each turn is the next
teacher's, judging only what it knows, showing world rows, a rough one its perturbed cast."""

import json

import numpy as np
import pytest

from sgim_nodes.core.experts import ARM_EXPERTS
from sgim_nodes.core.planar_arm import PlanarArm, teaching_set
from sgim_nodes.core.runner import main
from sgim_nodes.core.teacher_turns import TeacherTurns, turn_specs

ARM = PlanarArm(n_joints=7, seed=0)
TS = teaching_set(ARM)
NOTHING_REACHED = np.zeros((0, 2))


def turns(seed=0) -> TeacherTurns:
    return TeacherTurns(ARM_EXPERTS, TS.actions, TS.outcomes, seed, 50, 0.01,
                        "random-unreached", lambda: PlanarArm(n_joints=7, seed=9))


def test_each_turn_is_the_next_teachers_over_what_it_knows():
    t = turns()
    rows = {spec.name: set(spec.rows(TS.outcomes)) for spec in ARM_EXPERTS}
    for k in range(6):
        name = t.teacher_at(k)
        assert name == ARM_EXPERTS[k % 3].name
        turn = t.decide(NOTHING_REACHED)
        assert {c.index for c in turn.checks} == rows[name]  # world rows, its own only
        demo = turn.demonstration
        assert demo.teacher == name and demo.index in rows[name]
        assert turn.chosen == demo.index
        if name != "rough":  # a precise teacher shows the taught pair
            assert np.array_equal(demo.action, TS.actions[demo.index])
            assert np.array_equal(demo.outcome, TS.outcomes[demo.index])
        else:  # its own perturbation, and where that action lands in its world
            assert not np.array_equal(demo.action, TS.actions[demo.index])
            assert np.all(np.abs(demo.action) <= 1.0)


def test_a_teacher_whose_goals_are_all_reached_is_silent_on_its_turn():
    t = turns()
    west = ARM_EXPERTS[0].rows(TS.outcomes)
    turn = t.decide(TS.outcomes[west])  # every west goal reached, exactly
    assert turn.demonstration is None and all(c.reached for c in turn.checks)
    assert t.decide(TS.outcomes[west]).demonstration is not None  # east's turn: not all


def test_turns_are_deterministic_and_resume_where_they_were():
    a, b = turns(), turns()
    first = [a.decide(NOTHING_REACHED).chosen for _ in range(5)]
    assert first == [b.decide(NOTHING_REACHED).chosen for _ in range(5)]
    c = turns()
    c.resume_at(101)  # turns at 0, 50, 100 were taken
    assert c.turn == 3 and c.teacher_at(c.turn) == "west"
    with pytest.raises(ValueError, match="not on request"):
        a.decide(NOTHING_REACHED, asked=np.zeros(2))
    with pytest.raises(ValueError, match="unknown teacher"):
        turn_specs("planar-arm", "west,nobody")
    with pytest.raises(ValueError, match="distinct"):
        TeacherTurns(ARM_EXPERTS[:1] * 2, TS.actions, TS.outcomes, 0, 50, 0.01,
                     "random-unreached")


def test_the_runner_gives_sgim_d_its_teachers_in_turn(tmp_path):
    out = tmp_path / "run.jsonl"
    assert main(["--env", "planar-arm", "--learner", "sgim-d", "--movements", "200",
                 "--demonstration-period", "50", "--teacher-turns", "west,east,rough",
                 "--eval-every", "0", "--quiet", "--output", str(out)]) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert records[0]["teacher"]["turns"] == ["west", "east", "rough"]
    demos = [r for r in records if r["type"] == "demonstration"]
    assert [(d["movement"], d["teacher"]) for d in demos] == [
        (0, "west"), (50, "east"), (100, "rough"), (150, "west")]
    assert main(["--env", "planar-arm", "--learner", "sgim-d", "--movements", "10",
                 "--teacher-turns", "nobody", "--quiet", "--output", str(out)]) == 2
