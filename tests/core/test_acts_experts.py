"""Teachers as experts: the demonstration nearest the asked goal, "none there" beyond their
radius, a rough one's shown actions perturbed by its own stream, deterministic per seed."""

import math

import numpy as np
import pytest

from sgim_nodes.core.experts import ARM_EXPERTS, Expert, ExpertSpec, build_experts
from sgim_nodes.core.planar_arm import PlanarArm, teaching_set
from sgim_nodes.core.random_streams import member_rng

ARM = PlanarArm(n_joints=7, seed=0)
TS = teaching_set(ARM)


def expert(name="west", precision=0.0, radius=math.inf, world=None, seed=0):
    return Expert(name, TS.actions, TS.outcomes, member_rng(seed, "experts", name), precision,
                  radius, world)


def test_an_expert_answers_with_its_demonstration_nearest_the_goal():
    e = expert()
    goal = TS.outcomes[5] + np.array([0.01, -0.01])
    answer = e.answer(goal)
    d = np.linalg.norm(TS.outcomes - goal, axis=1)
    assert answer.index == int(np.argmin(d)) == 5
    assert answer.distance == pytest.approx(d.min())
    assert np.array_equal(answer.action, TS.actions[5])  # precise: shown as taught
    assert np.array_equal(answer.outcome, TS.outcomes[5])


def test_an_outcome_only_answer_shows_no_action():
    answer = expert().answer(TS.outcomes[3], with_action=False)
    assert answer.action is None and np.array_equal(answer.outcome, TS.outcomes[3])


def test_no_demonstration_within_the_radius_means_none_there_and_the_request_counts():
    e = expert(radius=0.05)
    far = np.array([-0.95, -0.95])  # a corner no teaching outcome comes near
    assert np.linalg.norm(TS.outcomes - far, axis=1).min() > 0.05
    assert e.answer(far) is None
    assert e.answer(TS.outcomes[0]) is not None
    assert (e.n_requests, e.n_unanswered) == (2, 1)


def test_a_rough_expert_shows_perturbed_actions_whose_casts_land_off():
    rough = expert("rough", precision=0.15, world=PlanarArm(n_joints=7, seed=1))
    misses = []
    for i in range(len(TS.outcomes)):
        answer = rough.answer(TS.outcomes[i])
        assert answer.index == i and not np.array_equal(answer.action, TS.actions[i])
        # the outcome shown is where the shown action lands, not the one it meant
        assert answer.outcome == pytest.approx(ARM.forward(answer.action))
        misses.append(np.linalg.norm(answer.outcome - TS.outcomes[i]))
    assert np.median(misses) > 10 * ARM.scale.noise


def test_an_imprecise_expert_without_a_world_is_refused():
    with pytest.raises(ValueError, match="needs a world"):
        expert("rough", precision=0.1)
    with pytest.raises(ValueError, match="precision must be"):
        expert(precision=-0.1)
    with pytest.raises(ValueError, match="radius must be > 0"):
        expert(radius=0.0)
    with pytest.raises(ValueError, match="bad teacher name"):
        expert(name="mimicry:west")


def test_the_same_seed_gives_the_same_answers_and_other_experts_do_not_interfere():
    def answers(seed, with_other):
        world = PlanarArm(n_joints=7, seed=2)
        rough = expert("rough", 0.2, world=world, seed=seed)
        other = expert("other", 0.2, world=PlanarArm(n_joints=7, seed=3), seed=seed)
        out = []
        for i in range(10):
            if with_other:
                other.answer(TS.outcomes[i])
            out.append(rough.answer(TS.outcomes[i]).action)
        return np.array(out)

    assert np.array_equal(answers(0, False), answers(0, True))
    assert not np.array_equal(answers(0, False), answers(1, False))


def test_the_arms_experts_split_the_teaching_set_by_region():
    experts = build_experts(ARM_EXPERTS, TS.actions, TS.outcomes, 0, ARM.scale.size,
                            lambda: PlanarArm(n_joints=7, seed=9))
    west, east, rough = experts["west"], experts["east"], experts["rough"]
    assert len(west.outcomes) + len(east.outcomes) == len(rough.outcomes) == len(TS.outcomes)
    assert west.outcomes[:, 0].max() < east.outcomes[:, 0].min()
    assert rough.precision > 0 and west.precision == east.precision == 0
    # an answer names the world's teaching-set row, as every demonstration does
    row = int(east.rows[3])
    answer = east.answer(TS.outcomes[row], with_action=False)
    assert answer.index == row and np.array_equal(answer.outcome, TS.outcomes[row])
    assert np.array_equal(east.actions[3], TS.actions[row]) and row != 3
    with pytest.raises(ValueError, match="part must be all"):
        ExpertSpec("x", "left").rows(TS.outcomes)
    with pytest.raises(ValueError, match="distinct"):
        build_experts([ARM_EXPERTS[0]] * 2, TS.actions, TS.outcomes, 0, 2.0)


def test_the_fishing_teachers_know_their_parts_of_the_lake():
    from sgim_nodes.core.acts_runner import experts_for
    from sgim_nodes.core.runner import build_world
    from sim_bridge.lake import DEFAULT_LAKE, PARTS

    world = build_world("fishing", 0)
    parts = [world.part_of(o) for o in world.teaching_outcomes]
    assert set(parts) <= set(PARTS)
    experts = experts_for("fishing", world, 0)
    assert sorted(experts) == ["centre", "rough", "west"]
    centre, west, rough = experts["centre"], experts["west"], experts["rough"]
    assert {world.part_of(o) for o in centre.outcomes} == {"basin", "north", "east"}
    assert {world.part_of(o) for o in west.outcomes} == {"west", "south", "pond"}
    assert len(centre.outcomes) + len(west.outcomes) == len(rough.outcomes) == len(parts)
    assert centre.precision == west.precision == 0.0 < rough.precision
    # The pond: west shows it, centre has nothing there.
    pond, _ = DEFAULT_LAKE.isolated_centre_radius()
    assert centre.answer(pond) is None
    assert world.part_of(west.answer(pond, with_action=False).outcome) == "pond"


def test_the_rough_fishing_teacher_lands_about_two_noise_units_off():
    """What the issue asks of `rough` (its outcomes about 2 noise units off), measured: each
    teaching entry asked twice, the shown action cast in the teacher's own world."""
    from sgim_nodes.core.acts_runner import experts_for
    from sgim_nodes.core.runner import build_world

    world = build_world("fishing", 3)
    experts = experts_for("fishing", world, 3)
    noise = world.scale.noise_rms

    def offsets(name: str) -> np.ndarray:
        expert, out = experts[name], []
        for goal in np.repeat(expert.outcomes, 2, axis=0):
            answer = expert.answer(goal)
            if answer is not None and answer.outcome is not None:
                out.append(np.linalg.norm(answer.outcome - goal))  # its own outcome
        return np.array(out) / noise

    rough, precise = offsets("rough"), np.concatenate([offsets("centre"), offsets("west")])
    assert 1.0 < np.median(rough) < 3.5, np.median(rough)
    assert np.median(precise) < 0.6, np.median(precise)


def test_a_spec_names_the_parts_it_knows_and_no_part_when_it_cuts_by_axis():
    assert ExpertSpec("w", "parts:west+south+pond").named_parts == ("west", "south", "pond")
    assert ExpertSpec("r", "all").named_parts == ExpertSpec("e", "high:0").named_parts == ()
