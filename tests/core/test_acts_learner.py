"""SGIM-ACTS on the planar arm: each strategy gets what it should, unanswered requests still
cost, a useless teacher ends up rarely asked, and a seed gives one run."""

import json
from collections import Counter

import numpy as np
import pytest

from sgim_nodes.core import runner
from sgim_nodes.core.acts_runner import experts_for, run_acts
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.experts import Expert
from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.planar_arm import PlanarArm, teaching_set
from sgim_nodes.core.random_streams import member_rng
from sgim_nodes.core.runner import build_world

ARM = PlanarArm(n_joints=7, seed=0)
TS = teaching_set(ARM)
OWN = {"goal_directed", "exploration"}


def learner(strategies, teachers=("t",), seed=0, config=None):
    return make_learner("sgim-acts", 7, 2, seed, config, ARM.scale, teachers=teachers,
                        strategies=strategies)


def teacher(name="t", radius=np.inf, actions=TS.actions, outcomes=TS.outcomes):
    return Expert(name, actions, outcomes, member_rng(0, "experts", name), radius=radius)


def prefill(made, n=30, seed=5):
    """Some random movements in memory, so that goal attempts have something to start from."""
    rng = np.random.default_rng(seed)
    for a in rng.uniform(-1, 1, (n, 7)):
        made.memory.add(a, ARM.forward(a), "random")


def test_mimicry_stores_the_teachers_demonstration_and_imitates_its_action():
    cfg = LearnerConfig(imitation_count=4, imitation_epsilon=0.05)
    made, expert = learner(["mimicry:t"], config=cfg), teacher()
    request = made.request()
    assert request.teacher == "t" and request.wants_action and request.index == 0
    with pytest.raises(RuntimeError, match="waiting for an answer"):
        made.next_action()
    answer = expert.answer(request.goal, request.wants_action)
    made.on_answer(request, answer)
    assert made.memory.labels == ["demonstration"]
    assert np.array_equal(made.memory.actions[0], answer.action)
    for _ in range(4):
        assert made.request() is None
        action, label = made.next_action()
        assert label == "imitation" and made.movement_strategy == "mimicry:t"
        assert np.linalg.norm(action - answer.action) < 0.05
        made.observe(action, ARM.execute(action))
    log = made.choices[0]
    assert log.answered and log.competence is not None and log.strategy == "mimicry:t"
    assert made.regions.counts().sum() == 1  # one episode, one competence, in its pair
    assert made.request() is not None  # the next episode asks again


def test_emulation_gets_only_the_outcome_and_reaches_it_with_its_own_movements():
    made, expert = learner(["emulation:t"]), teacher()
    prefill(made)
    shown = []
    for _ in range(60):
        while (request := made.request()) is not None:
            assert not request.wants_action
            answer = expert.answer(request.goal, request.wants_action)
            assert answer.action is None  # the teacher's action is never handed over
            shown.append(answer.index)
            made.on_answer(request, answer)
            assert np.array_equal(made.episode.process.goal, answer.outcome)  # its goal
        action, label = made.next_action()
        assert label in OWN
        made.observe(action, ARM.execute(action))
    labels = made.memory.labels[30:]
    assert set(labels) <= OWN and len(labels) == 60
    taught = {tuple(TS.actions[i]) for i in shown}
    assert not taught & {tuple(a) for a in made.memory.actions}


def test_a_teacher_with_nothing_near_answers_none_and_the_request_still_costs():
    cfg = LearnerConfig(acts_cost_mimicry=3.0)
    made = learner(["mimicry:t"], config=cfg)
    far = teacher(radius=1e-6)  # no teaching outcome within a micron of a random goal
    for k in range(5):
        request = made.request()
        assert request.index == k
        answer = far.answer(request.goal, request.wants_action)
        assert answer is None
        made.on_answer(request, answer)
        assert made.episode.done and made.n_movements == 0
    assert made.n_requests == 5 == made.n_unanswered == far.n_unanswered
    assert made.cost_spent == {"mimicry:t": 15.0}
    assert [c.answered for c in made.choices] == [False] * 5
    assert [c.competence for c in made.choices] == [-1.0] * 5  # no progress to show


@pytest.mark.slow
def test_a_teacher_that_never_helps_ends_up_rarely_asked():
    """Its single demonstration is the straight arm: imitating or emulating it never brings
    the learner nearer its goals once that point is known. With equal costs, only progress
    can keep it from the two thirds of the choices a uniform choice would give it; mode 2
    alone still gives it 0.2 * 2/3 = 0.13 of them."""
    world = build_world("planar-arm", 3, arm_joints=7)
    straight = np.zeros((1, 7))
    useless = Expert("useless", straight, ARM.forward(straight),
                     member_rng(3, "experts", "useless"))
    cfg = LearnerConfig(acts_cost_autonomous=1.0, acts_cost_emulation=1.0,
                        acts_cost_mimicry=1.0)
    made = make_learner("sgim-acts", 7, 2, 3, cfg, world.scale, teachers=("useless",))
    records = []
    run_acts(made, world, 1000, 0, {"useless": useless}, records.append)
    late = [c.strategy for c in made.choices if c.movement >= 500]
    share = sum(s != "autonomous" for s in late) / len(late)
    assert share < 1 / 4, Counter(late)


def run_records(seed, movements=150):
    world = build_world("planar-arm", seed, arm_joints=7)
    experts = experts_for("planar-arm", world, seed)
    made = make_learner("sgim-acts", 7, 2, seed, LearnerConfig(), world.scale,
                        teachers=tuple(experts))
    records = []
    run_acts(made, world, movements, 50, experts, records.append)
    return records


def test_the_same_seed_gives_the_same_run_with_requests_and_answers():
    first, again = run_records(4), run_records(4)
    assert json.dumps(first) == json.dumps(again)
    kinds = Counter(r["type"] for r in first)
    assert kinds["movement"] == 150 and kinds["request"] == kinds["answer"] > 0
    assert json.dumps(run_records(5)) != json.dumps(first)


def test_the_request_api_refuses_answers_it_did_not_ask_for():
    made = learner(["mimicry:t"])
    request = made.request()
    assert made.request() is request  # pending until answered
    with pytest.raises(ValueError, match="comes from 'other'"):
        made.on_answer(request, teacher("other").answer(request.goal))
    with pytest.raises(ValueError, match="the answer shows none"):
        made.on_answer(request, teacher().answer(request.goal, with_action=False))
    made.on_answer(request, None)
    with pytest.raises(ValueError, match="not the learner's pending request"):
        made.on_answer(request, None)


def test_an_episode_can_be_begun_with_a_strategy_and_goal_the_chooser_did_not_choose():
    from sgim_nodes.core.strategies import Strategy
    from sgim_nodes.core.strategy_choice import PairChoice

    made = learner(["autonomous", "mimicry:t"])
    leaf = made.regions.leaves[0]
    goal = np.array([0.3, -0.2])
    mimicry = made.strategies[1]
    request = made.begin(PairChoice(mimicry, goal, 0, 0, leaf))
    assert request.strategy == mimicry and np.array_equal(request.goal, goal)
    with pytest.raises(RuntimeError, match="current episode has not ended"):
        made.begin(PairChoice(made.strategies[0], goal, 0, 0, leaf))
    made.on_answer(request, None)  # "none there": the episode ends with competence -1
    assert (made.choices[-1].strategy, made.choices[-1].competence) == ("mimicry:t", -1.0)
    assert made.regions.history("mimicry:t", leaf).goals[0].tolist() == goal.tolist()
    with pytest.raises(ValueError, match="emulation:t is not one of the learner's"):
        made.begin(PairChoice(Strategy("emulation", "t", 5.0), goal, 0, 0, leaf))
    assert made.begin(PairChoice(made.strategies[0], goal, 0, 0, leaf)) is None  # autonomous
    assert made.request() is None and made.episode.choice.strategy.name == "autonomous"


def test_make_learner_refuses_unknown_teachers_and_strategies_for_other_learners():
    with pytest.raises(ValueError, match="unknown teacher 'north'"):
        learner(["mimicry:north"], teachers=("west",))
    with pytest.raises(ValueError, match="bad strategy 'copy:west'"):
        learner(["copy:west"], teachers=("west",))
    with pytest.raises(ValueError, match="saggriac takes no teachers"):
        make_learner("saggriac", 7, 2, 0, None, ARM.scale, teachers=("west",))
    assert [s.name for s in learner(None, teachers=()).strategies] == ["autonomous"]


def test_the_cli_runs_sgim_acts_and_writes_its_requests_and_answers(tmp_path, capsys):
    out = tmp_path / "acts.jsonl"
    assert runner.main(["--learner", "sgim-acts", "--movements", "80", "--seed", "2",
                        "--env", "planar-arm", "--arm-joints", "7", "--eval-every", "40",
                        "--output", str(out), "--quiet",
                        "--strategies", "autonomous,mimicry:west,emulation:rough"]) == 0
    records = [json.loads(line) for line in out.read_text().splitlines()]
    header, end = records[0], records[-1]
    assert header["learner"] == "sgim-acts" and end["type"] == "end"
    assert [s["name"] for s in header["strategies"]] == ["autonomous", "mimicry:west",
                                                         "emulation:rough"]
    moves = [r for r in records if r["type"] == "movement"]
    assert [m["index"] for m in moves] == list(range(80))
    assert {m["strategy"] for m in moves} <= {"autonomous", "mimicry:west", "emulation:rough"}
    requests = [r for r in records if r["type"] == "request"]
    answers = [r for r in records if r["type"] == "answer"]
    assert [a["request"] for a in answers] == [r["request"] for r in requests]
    assert len(requests) == end["n_requests"]
    for r, a in zip(requests, answers, strict=True):
        assert a["teacher"] == r["teacher"]
        if a["answered"] and not r["wants_action"]:
            assert a["action"] is None
    choices = [r for r in records if r["type"] == "strategy_choice"]
    assert sum(end["cost_spent"].values()) == pytest.approx(
        sum(header["strategies"][[s["name"] for s in header["strategies"]].index(
            c["strategy"])]["cost"] for c in choices))
    assert runner.main(["--learner", "sgim-acts", "--output", str(out), "--quiet",
                        "--arm-joints", "7", "--strategies", "mimicry:nobody"]) == 2
    assert "unknown teacher 'nobody'" in capsys.readouterr().err
    with pytest.raises(ValueError, match="no SGIM-ACTS teachers are specified for world "
                                         "'moon'"):
        experts_for("moon", None, 0)


def test_a_run_whose_teachers_never_answer_stops_instead_of_looping():
    made = learner(["mimicry:t"])
    world = build_world("planar-arm", 0, arm_joints=7)
    with pytest.raises(RuntimeError, match="no autonomous strategy"):
        run_acts(made, world, 5, 0, {"t": teacher(radius=1e-9)}, lambda record: None,
                 max_requests_in_a_row=50)
