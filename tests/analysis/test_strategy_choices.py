"""The SGIM-ACTS choice figures of issue 33: whom the learner asks where, and how often."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.analysis.strategy_choices import (
    Ask,
    asks_from_runner,
    expert_share,
    in_window,
    part_experts,
    strategy_shares,
    teacher_share,
)
from sgim_nodes.core.experts import ARM_EXPERTS, FISHING_EXPERTS, ExpertSpec


def test_each_part_has_the_one_precise_expert_that_names_it():
    assert part_experts(FISHING_EXPERTS) == {
        "basin": "centre", "north": "centre", "east": "centre",
        "west": "west", "south": "west", "pond": "west"}  # rough knows all, imprecisely
    assert part_experts(ARM_EXPERTS) == {}  # halves of the set, not parts of a world
    both = (ExpertSpec("a", "parts:basin+north"), ExpertSpec("b", "parts:north"))
    assert part_experts(both) == {"basin": "a"}  # north has no single expert


def test_shares_count_the_asks_of_the_last_window():
    parts = {(0.0, 0.0): "basin", (1.0, 0.0): "pond", (2.0, 0.0): "land"}

    def part_of(goal):
        return parts[tuple(float(x) for x in goal)]

    asks = [Ask(10, "rough", np.array([0.0, 0.0])),    # before the window
            Ask(900, "centre", np.array([0.0, 0.0])),  # the basin's expert
            Ask(950, "rough", np.array([1.0, 0.0])),   # the pond's is west
            Ask(990, "west", np.array([1.0, 0.0])),
            Ask(999, "west", np.array([2.0, 0.0]))]    # on land: nobody's part
    late = in_window(asks, 1000, 200)
    assert [a.movement for a in late] == [900, 950, 990, 999]
    share = expert_share(late, FISHING_EXPERTS, part_of)
    assert (share.hits, share.total, share.value) == (2, 3, pytest.approx(2 / 3))
    assert teacher_share(late, "rough").value == pytest.approx(1 / 4)
    assert teacher_share([], "rough").value is None
    assert len(in_window(asks, 1000, 0)) == 5


def test_a_runner_run_s_requests_and_choices_are_read_back():
    from sgim_nodes.core.acts_runner import experts_for, run_acts
    from sgim_nodes.core.learner_registry import make_learner
    from sgim_nodes.core.runner import build_world

    world = build_world("fishing", 3)
    experts = experts_for("fishing", world, 3)
    learner = make_learner("sgim-acts", world.env.action_dim, world.env.outcome_dim, 3,
                           scale=world.scale, teachers=tuple(experts))
    records: list[dict] = []
    world.goals = world.goals[:5]  # the evaluations are not what is tested here
    run_acts(learner, world, 150, 0, experts, records.append)
    asks = asks_from_runner(records)
    assert len(asks) == learner.n_requests > 0
    assert {a.teacher for a in asks} <= set(experts)
    windows = strategy_shares(records, 150, 50)
    assert [start for start, _ in windows] == [0, 50, 100]
    for _, shares in windows:
        assert sum(shares.values()) == pytest.approx(1.0)
    chosen = [r["strategy"] for r in records if r["type"] == "strategy_choice"]
    assert set().union(*(s for _, s in windows)) == set(chosen)
    from sim_bridge.lake import Lake

    share = expert_share(asks, FISHING_EXPERTS, Lake().part_of_outcome)
    owned = [a for a in asks if Lake().part_of_outcome(a.goal) != "land"]
    assert share.total == len(owned)


def _acts_run(tmp_path):
    from synthetic_study import ACTS_EPISODES, acts_records, run_messages, write_run

    from sgim_nodes.analysis.study import load_run_data

    evals = {0: 0.9, 10: 0.5, 20: 0.3}
    run_dir = write_run(tmp_path, "sgim-acts", 0, run_messages(
        "sgim-acts", 0, evals, extra=acts_records(ACTS_EPISODES)))
    return run_dir, load_run_data(run_dir)


def test_a_graph_run_s_requests_and_strategies_are_read_from_its_bag(tmp_path):
    from synthetic_study import ACTS_EPISODES, part_points

    from sgim_nodes.analysis.strategy_choices import asks_from_run, run_strategy_shares
    from sim_bridge.lake import Lake

    _, run = _acts_run(tmp_path)
    asks = asks_from_run(run)
    social = [(c, s, p) for c, s, p, _ in ACTS_EPISODES if ":" in s]
    assert [(a.movement, a.teacher) for a in asks] == [(c, s.partition(":")[2])
                                                       for c, s, _ in social]
    points = part_points()
    assert [tuple(a.goal) for a in asks] == [pytest.approx(points[p]) for _, _, p in social]
    assert run.ask_content.tolist()[:3] == ["means-and-goal", "goal-only", "means-and-goal"]
    assert run.demo_index.tolist() == [2, 12]  # the answers that showed what was asked for
    assert run.demo_source.tolist() == ["expert:centre", "expert:west"]
    assert run.choice_index.tolist() == [c for c, *_ in ACTS_EPISODES]
    windows = run_strategy_shares(run, 10)
    assert [start for start, _ in windows] == [0, 10]
    assert windows[0][1] == pytest.approx({"autonomous": 0.5, "mimicry:centre": 0.25,
                                           "emulation:rough": 0.25})
    assert sum(windows[1][1].values()) == pytest.approx(1.0)
    late = in_window(asks, run.total_movements, 10)
    assert len(late) == 5
    share = expert_share(late, FISHING_EXPERTS, Lake().part_of_outcome)
    assert (share.hits, share.total) == (3, 4)
    assert teacher_share(late, "rough").hits == 1


def test_the_cache_keeps_the_requests_and_an_older_cache_is_read_again(tmp_path, monkeypatch):
    from sgim_nodes.analysis import study as study_module
    from sgim_nodes.analysis.study import CACHE_NAME, CACHE_VERSION, bag_fingerprint, load_run_data

    run_dir, first = _acts_run(tmp_path)
    monkeypatch.setattr(study_module, "_read_run", lambda run_dir: 1 / 0)  # cached: not read
    second = load_run_data(run_dir)
    for name in ("ask_index", "ask_teacher", "ask_content", "ask_goal", "choice_index",
                 "choice_strategy", "choice_mode", "demo_source"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    monkeypatch.undo()
    # A cache of an older format, without these columns: its key names its version, so it
    # is not used.
    with np.load(run_dir / CACHE_NAME) as data:
        old = {k: data[k] for k in data.files
               if not k.startswith(("ask_", "choice_", "demo_source"))}
    old["fingerprint"] = np.array(bag_fingerprint(run_dir).replace(
        f"v{CACHE_VERSION}|", f"v{CACHE_VERSION - 1}|", 1))
    np.savez_compressed(run_dir / CACHE_NAME, **old)
    assert load_run_data(run_dir).ask_index.tolist() == first.ask_index.tolist()


def test_each_request_takes_the_mode_of_its_episode_s_choice():
    from types import SimpleNamespace

    from sgim_nodes.analysis.strategy_choices import asks_from_run, by_mode

    # Two "none there" mimicry requests to west at count 7 (no movement between them), then
    # an emulation request to centre at count 9 whose choice was not recorded.
    run = SimpleNamespace(
        choice_index=np.array([5, 7, 7, 7]),
        choice_strategy=np.array(["autonomous", "mimicry:west", "autonomous", "mimicry:west"]),
        choice_mode=np.array([1, 2, 3, 3], dtype=np.uint8),
        ask_index=np.array([7, 7, 9]), ask_teacher=np.array(["west", "west", "centre"]),
        ask_content=np.array(["means-and-goal", "means-and-goal", "goal-only"]),
        ask_goal=np.zeros((3, 2)))
    asks = asks_from_run(run)
    assert [a.mode for a in asks] == [2, 3, 0]
    groups = by_mode(asks)
    assert [len(groups[k]) for k in groups] == [1, 1, 3]


def test_a_run_without_requests_has_none(study):
    from sgim_nodes.analysis.strategy_choices import asks_from_run, run_strategy_shares
    from sgim_nodes.analysis.study import load_study

    run = load_study(study).runs_of("sgim-d")[0]
    assert asks_from_run(run) == [] and run_strategy_shares(run, 10) == []
    assert run.ask_goal.shape == (0, 2) and run.choice_strategy.shape == (0,)


def test_runs_weigh_the_same_in_the_mean_shares_and_counts():
    from collections import Counter

    from sgim_nodes.analysis.strategy_choices import mean_counts, mean_shares

    one = [(0, {"autonomous": 1.0}), (10, {"autonomous": 0.5, "mimicry:west": 0.5})]
    other = [(0, {"mimicry:west": 1.0})]  # chose nothing in the second window
    shares = mean_shares([one, other])
    assert shares == {0: {"autonomous": 0.5, "mimicry:west": 0.5},
                      10: {"autonomous": 0.5, "mimicry:west": 0.5}}
    counts = mean_counts([[(0, Counter(west=4))], [(0, Counter(west=2, rough=1)),
                                                   (10, Counter(rough=3))]])
    assert counts == {0: {"rough": 0.5, "west": 3.0}, 10: {"rough": 1.5, "west": 0.0}}
