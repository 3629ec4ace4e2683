"""The one validation of records: each rogue record of issue 12 is refused with its reason."""

from __future__ import annotations

import numpy as np
import pytest

from sgim_nodes.bag.record_checks import Limits, check, teaching_set_size
from sgim_nodes.bag.validation import IndexSequence, RunValidator, summarise
from tests.bag import samples

LIMITS = Limits(action_size=24, outcome_size=2, budget=300, teaching_set_size=26)
RNG = np.random.default_rng(0)


def kind(topic, record, limits=LIMITS):
    problem = check(topic, record, limits)
    return None if problem is None else problem.kind


def test_a_synthetic_run_passes_every_check():
    validator = RunValidator(Limits(budget=60, teaching_set_size=26))
    for topic, msg in samples.synthetic_run(60):
        assert validator.admit(topic, msg).ok, (topic, validator.quarantined)
    assert validator.quarantined == [] and validator.counts() == {}


@pytest.mark.parametrize("action, outcome, expected", [
    ([np.nan] + [0.0] * 23, [0.1, 0.1], "non-finite"),
    ([np.inf] + [0.0] * 23, [0.1, 0.1], "non-finite"),
    ([0.1] * 5, [0.1, 0.1], "size"),
    ([0.1] * 24, [1e300, -1e300], "out-of-bounds"),
    ([1.5] + [0.0] * 23, [0.1, 0.1], "out-of-bounds"),
    ([0.1] * 24, [0.1, 0.1, 0.1], "size"),
])
def test_bad_demonstrations_are_refused(action, outcome, expected):
    demo = samples.demonstration(1, 30, RNG)
    demo.action, demo.outcome = np.asarray(action), np.asarray(outcome)
    assert kind("demonstrations", demo) == expected


@pytest.mark.parametrize("content, action, outcome, expected", [
    ("goal-only", 0, 2, None), ("means-only", 24, 0, None), ("means-and-goal", 24, 2, None),
    # a part the content says is not shown, shown all the same: more than the mode gives
    ("goal-only", 24, 2, "bad-value"), ("means-only", 24, 2, "bad-value"),
    # a part the content says is shown, missing
    ("means-and-goal", 0, 2, "size"), ("means-and-goal", 24, 0, "size"),
    ("goal-only", 0, 3, "size"), ("means-only", 5, 0, "size"),
    # an unknown content, even with both parts (the field must say what is shown)
    ("both", 24, 2, "bad-value"), ("", 24, 2, "bad-value"),
])
def test_a_demonstration_shows_exactly_what_its_content_says(content, action, outcome,
                                                              expected):
    demo = samples.demonstration(1, 30, RNG)
    demo.content = content
    demo.action, demo.outcome = RNG.uniform(-1, 1, action), RNG.uniform(-1, 1, outcome)
    assert kind("demonstrations", demo) == expected
    assert kind("demonstrations_taken", demo) == expected


def test_a_demonstration_from_a_bag_before_the_content_field_showed_both():
    from types import SimpleNamespace

    from sgim_nodes.bag.records import DemonstrationRecord, to_record

    demo = samples.demonstration(1, 30, RNG)
    old = SimpleNamespace(**{name: getattr(demo, name) for name in (
        "stamp", "index", "movement_index", "action", "outcome", "teaching_set_index",
        "source")})
    assert kind("demonstrations", old) is None
    record = to_record(DemonstrationRecord, 5, old)
    assert (record.content, record.help_request, record.in_memory) == ("means-and-goal", 0,
                                                                        True)
    old.action = np.zeros(0)  # an old bag's goal-only demonstration cannot exist
    assert kind("demonstrations", old) == "size"


@pytest.mark.parametrize("change, expected", [
    ({}, None), ({"index": 0}, "bad-value"), ({"movement_index": 300}, "beyond-budget"),
    ({"movement_index": 301}, "beyond-budget"), ({"goal": np.zeros(0)}, "size"),
    ({"goal": np.array([0.2, 1.5])}, "out-of-bounds"),
    ({"goal": np.array([np.nan, 0.0])}, "non-finite"),
    ({"teacher": "west", "content": "goal-only"}, None),  # SGIM-ACTS asking an expert
    ({"teacher": "centre", "content": "means-and-goal"}, None),
    ({"teacher": "we-st"}, "bad-value"), ({"teacher": "2nd"}, "bad-value"),
    ({"content": "means-only"}, "bad-value"),  # a learner asks for what it can use
    ({"content": "anything"}, "bad-value"),
])
def test_help_requests_are_checked(change, expected):
    ask = samples.help_request(1, 150, RNG)
    for name, value in change.items():
        setattr(ask, name, value)
    assert kind("help_requests", ask) == expected


@pytest.mark.parametrize("teaching_index, expected", [
    (2**31 - 1, "unknown-teaching-index"), (-7, "unknown-teaching-index"),
    (26, "unknown-teaching-index"), (25, None), (-1, None)])
def test_a_teaching_index_must_name_an_entry(teaching_index, expected):
    demo = samples.demonstration(1, 30, RNG)
    demo.teaching_set_index = teaching_index
    assert kind("demonstrations", demo) == expected


def test_the_teachers_empty_word_is_valid_and_an_unknown_source_is_not():
    demo = samples.demonstration(0, 150, RNG)
    demo.action, demo.outcome, demo.index = np.zeros(0), np.zeros(0), 0
    assert kind("demonstrations", demo) is None
    demo.source = "rogue"
    assert kind("demonstrations", demo) == "bad-value"


@pytest.mark.parametrize("source, expected", [
    ("expert:west", None), ("expert:rough_2", None), ("expert:", "bad-value"),
    ("expert:we-st", "bad-value"), ("expert: west", "bad-value"), ("west", "bad-value")])
def test_an_experts_demonstration_names_it(source, expected):
    demo = samples.demonstration(1, 30, RNG)
    demo.source = source
    assert kind("demonstrations", demo) == expected


def test_the_packaged_teaching_set_is_known():
    assert teaching_set_size() == 29  # README_world.md: 29 demonstrations
    assert teaching_set_size("/no/such/file.npz") == 0


@pytest.mark.parametrize("goal, value, expected", [
    ([0.1, 0.1], np.nan, "non-finite"), ([0.1, 0.1], -1e9, "out-of-bounds"),
    ([0.1, 0.1], 0.5, "out-of-bounds"), ([0.1, 0.1, 0.1], -0.5, "size"),
    ([2.0, 0.0], -0.5, "out-of-bounds"), ([0.1, 0.1], -0.5, None)])
def test_bad_competences_are_refused(goal, value, expected):
    comp = samples.competence(1, 10, RNG)
    comp.goal, comp.competence = np.asarray(goal), value
    assert kind("competences", comp) == expected


@pytest.mark.parametrize("strategy, used, reached, value, expected", [
    ("emulation:west", 0, [], -1.0, None),  # SGIM-ACTS: "none there", no movement
    ("mimicry:rough", 5, [0.1, 0.2], -0.3, None),
    ("autonomous", 3, [0.1, 0.2], -0.3, None),
    ("autonomous", 0, [], -1.0, "bad-value"),  # only a social episode may spend nothing
    ("", 0, [], -1.0, "bad-value"),
    ("mimicry:west", 0, [0.1, 0.2], -1.0, "bad-value"),  # nothing moved, nothing reached
    ("mimicry:west", 0, [], -0.5, "bad-value"),
    ("imitate:west", 2, [0.1, 0.2], -0.5, "bad-value"),
    ("mimicry:9west", 2, [0.1, 0.2], -0.5, "bad-value")])
def test_a_competence_names_a_strategy_and_spends_movements(strategy, used, reached, value,
                                                              expected):
    comp = samples.competence(1, 10, RNG, strategy=strategy)
    comp.movements_used, comp.reached, comp.competence = used, np.asarray(reached), value
    assert kind("competences", comp) == expected


@pytest.mark.parametrize("strategy, expected", [
    ("", None), ("autonomous", None), ("emulation:centre", None), ("mimicry:", "bad-value"),
    ("autonomous:x", "bad-value")])
def test_a_goal_names_a_known_kind_of_strategy(strategy, expected):
    goal = samples.goal(1, 10, RNG)
    goal.strategy = strategy
    assert kind("goals", goal) == expected


def test_bad_movements_are_refused():
    good = samples.movement(1, RNG)
    assert kind("movements", good) is None
    nan = samples.movement(1, RNG)
    nan.outcome = np.array([np.nan, 0.0])
    assert kind("movements", nan) == "non-finite"
    outside = samples.movement(1, RNG)
    outside.action = np.full(24, 1.01)
    assert kind("movements", outside) == "out-of-bounds"
    failed_with_outcome = samples.movement(1, RNG, status=1)
    failed_with_outcome.outcome = np.array([0.1, 0.1])
    assert kind("movements", failed_with_outcome) == "size"
    evaluation = samples.movement(1, RNG, process=5)
    assert kind("movements", evaluation) == "bad-value"
    beyond = samples.movement(301, RNG)
    assert kind("movements", beyond) == "beyond-budget"
    assert kind("movements", samples.movement(0, RNG)) == "bad-value"


def test_evaluations_statuses_and_maps_are_checked():
    evaluation = samples.evaluation(100, RNG)
    assert kind("evaluations", evaluation) is None  # a NaN row: a cast with no touch-down
    evaluation.reached = np.full(6, 5.0)  # a touch-down on land may lie outside [-1, 1]^2
    assert kind("evaluations", evaluation) is None
    evaluation.mean_distance = 0.0
    assert kind("evaluations", evaluation) == "bad-value"
    short = samples.evaluation(100, RNG)
    short.distances = short.distances[:2]
    assert kind("evaluations", short) == "size"
    status = samples.run_status(10, 300, 0)
    assert kind("run_status", status) is None
    status.total_movements = 400  # not this run's budget
    assert kind("run_status", status) == "bad-value"
    region_map = samples.region_map(10, split=True)
    assert kind("region_map", region_map) is None
    region_map.regions[1].upper = np.array([np.inf, 1.0])
    assert kind("region_map", region_map) == "non-finite"


def test_movement_indices_follow_the_runs_count():
    seq = IndexSequence("movement")
    assert seq.admit(1).ok and seq.admit(2).ok
    assert seq.admit(2_000_000).problem.kind == "jumps-ahead"
    assert seq.admit(int(1e9)).problem.kind == "jumps-ahead"
    assert seq.count == 2
    assert seq.admit(2).problem.kind == "duplicate"  # same attempt: not a re-execution
    assert seq.admit(1, attempt=1).problem.kind == "duplicate"  # not the latest movement
    verdict = seq.admit(2, attempt=1)  # the simulator client retried movement 2
    assert verdict.ok and verdict.supersedes
    assert seq.admit(2, attempt=1).problem.kind == "duplicate"
    assert seq.admit(3).ok
    seq.resync()  # a damaged part of the bag was skipped
    assert seq.admit(10).ok and seq.admit(11).ok and seq.admit(13).problem.kind == "jumps-ahead"


def test_the_validator_counts_by_topic_and_kind_and_summarises():
    validator = RunValidator(LIMITS)
    for i in (1, 2, 3):
        assert validator.admit("/movements", samples.movement(i, RNG)).ok
    for i in (2, 3, 9):
        validator.admit("/movements", samples.movement(i, RNG))
    comp = samples.competence(1, 3, RNG)
    comp.competence = float("nan")
    validator.admit("/competences", comp)
    assert validator.counts() == {"competences": {"non-finite": 1},
                                  "movements": {"duplicate": 2, "jumps-ahead": 1}}
    lines = summarise(validator.quarantined, limit=2)
    assert lines[0].startswith("movements record 2 quarantined: movement 2 again")
    assert lines[-1] == "... and 2 more: 1 movements (jumps-ahead), 1 competences (non-finite)"


def test_limits_come_from_a_runs_parameters():
    limits = Limits.for_run({"movements": 450, "action_size": 24, "outcome_size": 2})
    assert limits.budget == 450 and limits.teaching_set_size == 29
