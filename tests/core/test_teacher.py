"""The teacher demonstrates only unreached teaching goals, every P movements."""

import numpy as np
import pytest

from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.planar_arm import PlanarArm
from sgim_nodes.core.social_config import SocialConfig
from sgim_nodes.core.teaching import (
    ABILITY,
    DEFAULT_REACHED_RULE,
    FARTHEST_UNREACHED,
    NEAREST_UNREACHED,
    OWN_MOVEMENTS,
    RANDOM_UNREACHED,
    TEACHER_CHOICES,
    Teacher,
    cast_distance,
    learner_progress,
)

ACTIONS = np.array([[0.0, 0.0], [0.1, 0.1], [0.2, 0.2]])
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5]])


def test_due_every_period():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), period=150)
    assert [m for m in range(0, 451) if t.due(m)] == [0, 150, 300, 450]


def test_chooses_only_unreached_goals_at_random():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), tolerance=0.05)
    reached = np.array([[0.01, 0.0], [0.9, 0.9]])  # goal 0 within 0.05, others not
    assert t.unreached(reached).tolist() == [1, 2]
    picks = [t.choose(reached).index for _ in range(400)]
    assert set(picks) == {1, 2}
    assert np.mean(np.array(picks) == 1) == pytest.approx(0.5, abs=0.1)
    demo = t.choose(reached)
    assert np.array_equal(demo.action, ACTIONS[demo.index])
    assert np.array_equal(demo.outcome, OUTCOMES[demo.index])


def test_tolerance_boundary_and_callable():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), tolerance=0.1)
    # distance exactly 0.1 counts as reached ("within" the tolerance)
    assert 1 not in t.unreached(np.array([[0.5, 0.6]])).tolist()
    assert 1 in t.unreached(np.array([[0.5, 0.61]])).tolist()

    def closest(goal):
        return 0.0 if goal[0] < 0 else 1.0  # only goal 2 reached

    assert t.unreached(closest).tolist() == [0, 1]


def test_none_when_everything_is_reached_and_all_when_nothing():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0))
    assert t.choose(OUTCOMES + 0.01) is None
    assert t.unreached(np.empty((0, 2))).tolist() == [0, 1, 2]


def test_same_seed_same_choices():
    a = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(7))
    b = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(7))
    r = np.empty((0, 2))
    assert [a.choose(r).index for _ in range(20)] == [b.choose(r).index for _ in range(20)]


def test_invalid_teacher():
    with pytest.raises(ValueError):
        Teacher(ACTIONS, OUTCOMES[:2], np.random.default_rng(0))
    with pytest.raises(ValueError):
        Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0), period=0)


def test_own_movements_rule_a_demonstrated_goal_stays_unreached_until_its_own_movements_reach_it():
    arm = PlanarArm(seed=0)
    learner = make_learner("sgim-d", 12, 2, 0, None, arm.scale)
    goal_action = np.full(12, 0.3)
    goal = arm.forward(goal_action)
    t = Teacher(np.array([goal_action]), np.array([goal]), np.random.default_rng(0),
                tolerance=0.01)
    learner.on_demonstration(goal_action, goal)
    for _ in range(learner.config.imitation_count):  # the imitations land on the goal too
        a, label = learner.next_action()
        assert label == "imitation"
        learner.observe(a, arm.execute(a))
    def own_rule():
        return learner_progress(OWN_MOVEMENTS, learner.inverse, learner.own_outcomes, None)

    assert t.choose(own_rule()) is not None  # still unreached: shown again
    learner.memory.add(goal_action, goal, "goal_directed")  # its own goal-directed cast
    assert t.choose(own_rule()) is None


def test_the_runner_keeps_teaching_while_a_goal_is_unreached():
    import json

    from sgim_nodes.core import runner

    world = runner.build_world("planar-arm", 0)
    learner = runner.make_learner("sgim-d", 12, 2, 0, None, world.scale)
    records: list[dict] = []
    social = SocialConfig(demonstration_period=50,
                          tolerance_noise=0.01)  # a tolerance too tight to ever reach
    runner.run(learner, world, 600, 0, 0, records.append, social)
    demos = [r for r in records if r["type"] == "demonstration"]
    assert [d["movement"] for d in demos] == list(range(0, 600, 50))
    assert json.dumps(demos[0])  # plain JSON


def _learner_and_goal(arm):
    """An SGIM-D learner on the arm and one teaching goal with the action that reaches it."""
    learner = make_learner("sgim-d", 12, 2, 0, None, arm.scale)
    goal_action = np.full(12, 0.3)
    return learner, goal_action, arm.forward(goal_action)


def test_ability_is_the_default_rule():
    assert DEFAULT_REACHED_RULE == ABILITY


def test_ability_keeps_teaching_a_goal_reached_once_by_luck_that_the_inverse_model_misses():
    arm = PlanarArm(seed=0)  # the teacher's world, noise-free
    learner, goal_action, goal = _learner_and_goal(arm)
    t = Teacher(np.array([goal_action]), np.array([goal]), np.random.default_rng(0),
                tolerance=0.05)
    # One lucky landing: its own movement came down on the goal, but the action really
    # lands far away (the world's noise carried it there once).
    lucky_action = np.full(12, -0.4)
    assert np.linalg.norm(arm.forward(lucky_action) - goal) > 0.5
    learner.memory.add(lucky_action, goal, "goal_directed")
    assert t.choose(learner_progress(OWN_MOVEMENTS, learner.inverse, learner.own_outcomes,
                                     None)) is None  # the old rule: reached, silent
    ability = learner_progress(ABILITY, learner.inverse, learner.own_outcomes, arm)
    assert ability(goal) > 0.5  # the inverse model's cast misses it
    assert [t.choose(ability).index for _ in range(3)] == [0, 0, 0]  # taught, again


def test_ability_stops_teaching_a_goal_the_learner_can_reach():
    arm = PlanarArm(seed=0)
    learner, goal_action, goal = _learner_and_goal(arm)
    other_action = np.full(12, -0.4)
    t = Teacher(np.array([goal_action, other_action]),
                np.array([goal, arm.forward(other_action)]), np.random.default_rng(0),
                tolerance=0.05)
    learner.memory.add(goal_action + 0.001, arm.forward(goal_action + 0.001), "goal_directed")
    ability = learner_progress(ABILITY, learner.inverse, learner.own_outcomes, arm)
    assert ability(goal) <= 0.05
    assert {t.choose(ability).index for _ in range(20)} == {1}  # only the unreached one
    learner.memory.add(other_action, arm.forward(other_action), "exploration")
    assert t.choose(ability) is None


def test_ability_casts_touch_neither_the_learners_memory_nor_its_world():
    world = PlanarArm(seed=1, noise=0.02)
    teacher_world = PlanarArm(seed=2, noise=0.02)
    learner, goal_action, goal = _learner_and_goal(world)
    for _ in range(30):
        a, _label = learner.next_action()
        learner.observe(a, world.execute(a))
    before = (len(learner.memory), learner.n_movements, world.rng.bit_generator.state)
    teacher_state = teacher_world.rng.bit_generator.state
    t = Teacher(np.array([goal_action]), np.array([goal]), np.random.default_rng(0))
    t.choose(learner_progress(ABILITY, learner.inverse, learner.own_outcomes, teacher_world))
    assert (len(learner.memory), learner.n_movements, world.rng.bit_generator.state) == before
    assert teacher_world.rng.bit_generator.state != teacher_state  # it cast in its own world


def test_cast_distance_measures_a_landing_on_land_and_a_failure():
    from types import SimpleNamespace

    from sgim_nodes.core.environment import Status

    class Land:  # every cast comes down on land at `touchdown` (None: never comes down)
        action_dim, outcome_dim = 2, 2

        def __init__(self, touchdown):
            self.touchdown = touchdown

        def execute(self, action):
            return SimpleNamespace(outcome=None, status=Status.NO_CONTACT,
                                   touchdown=self.touchdown)

    goal = np.array([0.0, 0.0])
    assert cast_distance(lambda g: g, Land(np.array([0.3, 0.4])))(goal) == pytest.approx(0.5)
    assert cast_distance(lambda g: g, Land(None))(goal) == np.inf


def test_the_runner_counts_no_teacher_cast_as_a_movement():
    from sgim_nodes.core import runner

    world = runner.build_world("arm-7", 0)
    learner = runner.make_learner("sgim-d", world.env.action_dim, 2, 0, None, world.scale)
    records: list[dict] = []
    runner.run(learner, world, 300, 0, 0, records.append, SocialConfig(demonstration_period=50))
    moves = [r for r in records if r["type"] == "movement"]
    demos = [r for r in records if r["type"] == "demonstration"]
    assert len(moves) == learner.n_movements == 300
    assert len(learner.memory) == sum(m["outcome"] is not None for m in moves) + len(demos)
    assert learner.memory.labels.count("demonstration") == len(demos) > 0


def test_unknown_rule_is_refused():
    from sgim_nodes.core import runner

    world = runner.build_world("planar-arm", 0)
    learner = runner.make_learner("sgim-d", 12, 2, 0, None, world.scale)
    with pytest.raises(ValueError, match="reached_rule"):
        runner.run(learner, world, 10, 0, 0, lambda r: None, SocialConfig(reached_rule="lucky"))


# --- which unreached goal (issue 14: teacher_choice) ------------------------------------------

FIVE = np.array([[0.0, 0.0], [0.2, 0.0], [0.5, 0.0], [0.9, 0.0], [-0.6, 0.0]])


def _five(choice: str, seed: int = 0) -> Teacher:
    return Teacher(np.zeros((5, 3)), FIVE, np.random.default_rng(seed), tolerance=0.05,
                   choice=choice)


def test_farthest_and_nearest_unreached_pick_by_the_learners_distance():
    reached = np.array([[0.01, 0.0], [0.25, 0.0]])  # goal 0 reached; 1 at 0.05 is reached too
    d = _five(RANDOM_UNREACHED).distances(reached)
    assert d.round(3).tolist() == [0.01, 0.05, 0.25, 0.65, 0.61]
    assert {_five(FARTHEST_UNREACHED).choose(reached).index for _ in range(20)} == {3}
    assert {_five(NEAREST_UNREACHED).choose(reached).index for _ in range(20)} == {2}
    picks = {_five(RANDOM_UNREACHED, s).choose(reached).index for s in range(40)}
    assert picks == {2, 3, 4}  # the paper's rule: any unreached one, never 0 or 1


def test_choice_ties_are_broken_at_random_and_reached_goals_never_chosen():
    nothing = np.empty((0, 2))  # nothing reached: every goal infinitely far, all tied
    for choice in TEACHER_CHOICES:
        picks = {_five(choice, s).choose(nothing).index for s in range(60)}
        assert picks == {0, 1, 2, 3, 4}, choice
    for choice in TEACHER_CHOICES:
        assert _five(choice).choose(FIVE + 0.01) is None


def test_unknown_choice_refused():
    with pytest.raises(ValueError, match="teacher choice"):
        _five("best-guess")


@pytest.mark.parametrize("choice", [FARTHEST_UNREACHED, NEAREST_UNREACHED])
def test_the_runner_demonstrates_what_the_choice_rule_picks(choice):
    """On the planar arm, with the own-movements rule (so that the learner's state at each turn
    can be rebuilt from the run's own records): every demonstration is the unreached teaching
    goal farthest from (nearest to) the learner's own outcomes at that turn."""
    from sgim_nodes.core import runner
    from sgim_nodes.core.teaching import OWN_PROCESSES

    world = runner.build_world("planar-arm", 3)
    learner = runner.make_learner("sgim-d", 12, 2, 3, None, world.scale)
    records: list[dict] = []
    social = SocialConfig(demonstration_period=40, tolerance_noise=1.0,
                          reached_rule=OWN_MOVEMENTS, teacher_choice=choice)
    runner.run(learner, world, 400, 0, 3, records.append, social)
    tolerance = 1.0 * world.scale.noise
    goals = world.teaching_outcomes
    demos = [r for r in records if r["type"] == "demonstration"]
    assert len(demos) >= 5
    for demo in demos:
        own = np.array([r["outcome"] for r in records if r["type"] == "movement"
                        and r["index"] < demo["movement"] and r["outcome"] is not None
                        and r["label"] in OWN_PROCESSES]).reshape(-1, 2)
        d = (np.full(len(goals), np.inf) if len(own) == 0 else
             np.linalg.norm(goals[:, None, :] - own[None, :, :], axis=2).min(axis=1))
        unreached = np.flatnonzero(d > tolerance)
        best = d[unreached].max() if choice == FARTHEST_UNREACHED else d[unreached].min()
        assert demo["teaching_index"] in unreached
        assert d[demo["teaching_index"]] == best


# --- the turn's checks (issue 31: the teacher's checks are recorded) -------------------------


def _arm_learner_after(movements: int, seed: int = 0):
    """The planar arm's world and an SGIM-D learner that made `movements` movements in it."""
    from sgim_nodes.core import runner

    world = runner.build_world("planar-arm", seed)
    learner = make_learner("sgim-d", world.env.action_dim, 2, seed, None, world.scale)
    for _ in range(movements):
        a, _label = learner.next_action()
        learner.observe(a, world.env.execute(a))
    return world, learner


@pytest.mark.parametrize("rule", [ABILITY, OWN_MOVEMENTS])
@pytest.mark.parametrize("choice", TEACHER_CHOICES)
def test_a_turn_s_checks_reproduce_its_unreached_set_and_its_decision(rule, choice):
    """On the planar arm a turn returns one check per teaching goal, whose verdicts are the
    unreached set measured independently, and from which the decision is redone: the entries
    its distances allow (distance > tolerance, the choice rule), and the draw with the same
    stream. The teacher's world is noise-free, so a second cast lands where the first did."""
    from sgim_nodes.core.teaching import Check, eligible

    world, learner = _arm_learner_after(120)
    tolerance = 0.05
    goals, actions = world.teaching_outcomes, world.teaching_actions

    def progress():
        return learner_progress(rule, learner.inverse, learner.own_outcomes,
                                world.make_teacher_env() if rule == ABILITY else None)

    turn = Teacher(actions, goals, np.random.default_rng(5), tolerance=tolerance,
                   choice=choice).decide(progress())
    assert [c.index for c in turn.checks] == list(range(len(goals)))
    own = learner.own_outcomes()
    for check in turn.checks:
        assert isinstance(check, Check) and np.array_equal(check.goal, goals[check.index])
        if rule == ABILITY:  # the learner's action, and where the arm lands it
            assert np.array_equal(check.action, learner.inverse(check.goal))
            assert np.allclose(check.landed, world.env.forward(check.action), atol=1e-12)
            assert check.own_outcomes == 0
        else:  # no cast: the learner's own outcome nearest the goal
            assert check.action is None and check.own_outcomes == len(own)
            assert any(np.array_equal(check.landed, y) for y in own)
            assert check.distance == np.linalg.norm(own - check.goal, axis=1).min()
        assert check.distance == pytest.approx(np.linalg.norm(check.landed - check.goal),
                                               abs=1e-12)
        assert check.reached == (check.distance <= check.tolerance == tolerance)
    # The verdicts are the unreached set the teacher measures afresh.
    unreached = Teacher(actions, goals, np.random.default_rng(0),
                        tolerance=tolerance).unreached(progress())
    assert [c.index for c in turn.checks if not c.reached] == unreached.tolist()
    assert 0 < len(unreached) < len(goals)  # both verdicts are part of what is tested
    # The decision, redone from the checks alone: what they allow, drawn as the teacher draws.
    pool = eligible(np.array([c.distance for c in turn.checks]), tolerance, choice)
    assert set(pool) <= set(unreached)
    assert turn.chosen == int(np.random.default_rng(5).choice(pool))
    assert np.array_equal(turn.demonstration.action, actions[turn.chosen])


def test_an_answer_s_checks_redo_it_and_a_silent_turn_s_say_why():
    from sgim_nodes.core.teaching import eligible

    world, learner = _arm_learner_after(120)
    goals = world.teaching_outcomes
    ability = learner_progress(ABILITY, learner.inverse, learner.own_outcomes,
                               world.make_teacher_env())
    asked = np.array([0.3, -0.2])
    turn = Teacher(world.teaching_actions, goals, np.random.default_rng(2),
                   tolerance=0.05).decide(ability, asked)
    assert np.array_equal(turn.asked, asked)
    pool = eligible(np.array([c.distance for c in turn.checks]), 0.05, RANDOM_UNREACHED,
                    np.array([c.goal for c in turn.checks]), asked)
    unreached = [c.index for c in turn.checks if not c.reached]
    gap = np.linalg.norm(goals[unreached] - asked, axis=1)
    assert pool.tolist() == np.array(unreached)[gap == gap.min()].tolist()
    assert turn.chosen == int(np.random.default_rng(2).choice(pool))
    # Every goal within a lenient tolerance: silent, and every check says it was reached.
    silent = Teacher(world.teaching_actions, goals, np.random.default_rng(2),
                     tolerance=10.0).decide(ability)
    assert silent.demonstration is None and silent.chosen == -1
    assert all(c.reached for c in silent.checks) and len(silent.checks) == len(goals)
    # Nothing reached at all: every distance infinite, nothing landed.
    empty = Teacher(world.teaching_actions, goals, np.random.default_rng(2)).decide(
        np.empty((0, 2)))
    assert all(c.distance == np.inf and c.landed is None and not c.reached
               for c in empty.checks)


def test_the_runner_writes_each_turn_s_checks_and_they_redo_its_demonstrations():
    """The runner's "teacher_check" records, one per teaching goal before each turn's
    demonstration, redo every turn from the run's seed: the entry shown, or the silence."""
    import json

    from sgim_nodes.core import runner
    from sgim_nodes.core.random_streams import component_rng
    from sgim_nodes.core.teaching import eligible

    seed, period, movements = 1, 30, 300
    world = runner.build_world("planar-arm", seed)
    learner = runner.make_learner("sgim-d", 12, 2, seed, None, world.scale)
    records: list[dict] = []
    social = SocialConfig(demonstration_period=period,
                          tolerance_noise=20.0)  # lenient: 3 of the 10 turns are silent
    runner.run(learner, world, movements, 0, seed, records.append, social)
    assert all(json.loads(json.dumps(r, allow_nan=False)) == r for r in records)  # plain JSON
    checks = [r for r in records if r["type"] == "teacher_check"]
    shown = {r["movement"]: r["teaching_index"] for r in records
             if r["type"] == "demonstration"}
    n = len(world.teaching_outcomes)
    assert len(checks) == n * len(range(0, movements, period))
    rng = component_rng(seed, "teacher")
    silent = 0
    for start in range(0, len(checks), n):
        turn = checks[start: start + n]
        k = turn[0]["movement"]
        assert [c["movement"] for c in turn] == [k] * n
        assert [c["teaching_index"] for c in turn] == list(range(n))
        distances = np.array([np.inf if c["distance"] is None else c["distance"]
                              for c in turn])
        assert [c["reached"] for c in turn] == (distances <= turn[0]["tolerance"]).tolist()
        pool = eligible(distances, turn[0]["tolerance"], turn[0]["choice"])
        expected = int(rng.choice(pool)) if len(pool) else None
        assert shown.get(k) == expected, k
        assert [c["teaching_index"] for c in turn if c["chosen"]] == (
            [] if expected is None else [expected])
        silent += expected is None
        # Written before the turn's demonstration, after the movement before it.
        at = records.index(turn[0])
        assert records[at - 1]["type"] != "movement" or records[at - 1]["index"] == k - 1
    assert 0 < silent < movements // period  # silences and demonstrations both redone
