"""The human teacher's command language: parsing, validation and decisions, without ROS."""

from __future__ import annotations

import re

import numpy as np
import pytest

from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.teaching import Teacher
from teacher.human_commands import (
    HELP,
    CommandError,
    GoalPoint,
    Help,
    ListGoals,
    Quit,
    Send,
    Status,
    Teach,
    YamlFile,
    parse,
)
from teacher.human_decisions import (
    DEFAULT_TOLERANCE,
    ExecuteFirst,
    LearnerState,
    Reply,
    SendDemonstration,
    TeachingLibrary,
    executed_demonstration,
    load_action_file,
    prompt,
    unexecuted_demonstration,
)

A = 24
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5], [0.5, -0.5]])
ACTIONS = np.array([np.full(A, 0.1 * (i + 1)) for i in range(len(OUTCOMES))])


@pytest.fixture
def library() -> TeachingLibrary:
    return TeachingLibrary(ACTIONS, OUTCOMES, tolerance=0.05)


@pytest.fixture
def state() -> LearnerState:
    return LearnerState(action_size=A)


# --- parsing -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("line", "command"),
    [
        ("help", Help()),
        ("?", Help()),
        ("  HELP  ", Help()),
        ("quit", Quit()),
        ("exit", Quit()),
        ("list", ListGoals()),
        ("status", Status()),
        ("teach 3", Teach(3)),
        ("teach -1", Teach(-1)),  # parsed; refused later with the set's range
        ("goal 0.1 -0.2", GoalPoint((0.1, -0.2))),
        ("goal 1 -1", GoalPoint((1.0, -1.0))),
        ("goal 1e-1 .5", GoalPoint((0.1, 0.5))),
        ("send", Send()),
        ("yaml demo.yaml", YamlFile("demo.yaml")),
        ("yaml 'my demo.yaml'", YamlFile("my demo.yaml")),
    ],
)
def test_good_lines(line, command):
    assert parse(line) == command


@pytest.mark.parametrize("line", ["", "   ", "\t"])
def test_blank_lines_are_nothing(line):
    assert parse(line) is None


@pytest.mark.parametrize(
    ("line", "words"),
    [
        ("fly", ["unknown command 'fly'", "help"]),
        ("list 3", ["'list' takes no arguments"]),
        ("quit now", ["'quit' takes no arguments"]),
        ("teach", ["'teach' needs one", "got 0"]),
        ("teach 1 2", ["'teach' needs one", "got 2"]),
        ("teach x", ["'x' is not a whole number"]),
        ("teach 1.5", ["'1.5' is not a whole number"]),
        ("goal", ["'goal' needs 2 numbers", "got 0"]),
        ("goal 0.1", ["'goal' needs 2 numbers", "got 1"]),
        ("goal 0.1 0.2 0.3", ["got 3"]),
        ("goal a 0.2", ["goal X is 'a', not a number"]),
        ("goal 0.1 nan", ["goal Y is NaN"]),
        ("goal inf 0", ["goal X is infinite"]),
        ("goal 1.5 0", ["goal X = 1.5 is outside [-1, 1]"]),
        ("goal 0 -1.01", ["goal Y = -1.01 is outside [-1, 1]"]),
        ("yaml", ["'yaml' needs one file name", "got 0"]),
        ("yaml a b", ["got 2"]),
        ("yaml 'open", ["cannot read the line", "quotation"]),
    ],
)
def test_bad_lines_name_the_problem(line, words):
    with pytest.raises(CommandError) as error:
        parse(line)
    for w in words:
        assert w in str(error.value)


# --- the learner as heard -----------------------------------------------------------------


def test_state_counts_movements_and_keeps_landed_ones(state):
    assert state.add_movement(1, True, np.zeros(A), [0.1, 0.2]) is None
    assert state.add_movement(2, False, np.zeros(A), []) is None  # failed cast: counted only
    assert state.add_movement(4, True, np.zeros(A), [0.3, 0.4]) is None
    assert state.movement_count == 4 and state.indices == [1, 4]
    assert state.reached().tolist() == [[0.1, 0.2], [0.3, 0.4]]
    assert "size" in state.add_movement(5, True, np.zeros(3), [0.1, 0.2])
    assert "non-finite" in state.add_movement(6, True, np.zeros(A), [np.nan, 0.0])
    assert state.movement_count == 6 and len(state.outcomes) == 2
    state.add_movement(3, True, np.zeros(A), [0.0, 0.0])  # late arrival keeps the maximum
    assert state.movement_count == 6


def test_status_and_prompt(library, state):
    text = library.decide(Status(), state).text
    assert "no evaluation yet" in text and "movements: 0" in text
    assert "demonstrations given: 0" in text
    state.evaluation = (250, 0.1234567)
    state.add_movement(251, False, [], [])
    state.demonstrations = 2
    text = library.decide(Status(), state).text
    assert "0.1235 (at movement 250)" in text and "movements: 251" in text
    assert "demonstrations given: 2" in text and "listening to demonstrations: 0" in text
    assert prompt(state) == "[movements 251 | error 0.123 | demos 2] human> "


def test_help_and_quit(library, state):
    assert library.decide(Help(), state) == Reply(HELP)
    for name in ("list", "status", "teach", "goal", "send", "yaml", "quit"):
        assert name in HELP
    assert library.decide(Quit(), state) == Quit()


# --- list and teach ------------------------------------------------------------------------


def test_default_tolerance_is_the_automatic_teachers():
    t = Teacher(ACTIONS, OUTCOMES, np.random.default_rng(0))
    assert t.tolerance == DEFAULT_TOLERANCE


def test_list_shows_only_unreached_goals_with_their_outcome(library, state):
    text = library.decide(ListGoals(), state).text
    assert "4 of 4" in text and "nothing reached yet" in text
    state.add_movement(1, True, np.zeros(A), [0.5, 0.53])  # entry 1 within 0.05
    state.add_movement(2, True, np.zeros(A), [-0.5, 0.6])  # entry 2 at 0.1: not reached
    lines = library.decide(ListGoals(), state).text.splitlines()
    assert lines[0] == "3 of 4 teaching goals not reached within 0.05:"
    numbered = [int(line.split(":")[0]) for line in lines[1:]]
    assert numbered == [0, 2, 3]
    assert "(-0.500, +0.500)" in lines[2] and "closest 0.100" in lines[2]
    for y in OUTCOMES:
        state.add_movement(9, True, np.zeros(A), y)
    assert "all 4 teaching goals are reached" in library.decide(ListGoals(), state).text


def test_teach_sends_the_entry(library, state):
    state.add_movement(1, True, np.zeros(A), [0.5, 0.5])
    demo = library.decide(Teach(2), state)
    assert isinstance(demo, SendDemonstration) and demo.teaching_set_index == 2
    assert np.array_equal(demo.action, ACTIONS[2]) and np.array_equal(demo.outcome, OUTCOMES[2])
    assert "entry 2" in demo.text and "already" not in demo.text
    assert "already reached" in library.decide(Teach(1), state).text


@pytest.mark.parametrize("index", [-1, 4, 100])
def test_teach_out_of_range(library, state, index):
    with pytest.raises(CommandError, match=f"no teaching-set entry {index}: entries are 0 to 3"):
        library.decide(Teach(index), state)


@pytest.mark.parametrize(
    ("actions", "outcomes"),
    [
        (np.zeros((0, A)), np.zeros((0, 2))),
        (np.zeros((3, A)), np.zeros((2, 2))),
        (np.zeros((3, A)), np.zeros((3, 3))),
        (np.zeros(A), np.zeros(2)),
        (np.full((1, A), np.nan), np.zeros((1, 2))),
    ],
)
def test_bad_teaching_sets_are_refused(actions, outcomes):
    with pytest.raises(ValueError, match="teaching set"):
        TeachingLibrary(actions, outcomes, tolerance=0.05)


def test_negative_tolerance_is_refused():
    with pytest.raises(ValueError, match="tolerance"):
        TeachingLibrary(ACTIONS, OUTCOMES, tolerance=-0.1)


# --- goal: the library's most reliable pair -------------------------------------------------


def test_goal_picks_a_teaching_entry_when_it_is_the_most_reliable(library, state):
    demo = library.decide(GoalPoint((0.45, 0.5)), state)
    assert demo.teaching_set_index == 1
    assert np.array_equal(demo.action, ACTIONS[1]) and np.array_equal(demo.outcome, OUTCOMES[1])
    assert "teaching-set entry 1" in demo.text and "0.050 from the goal" in demo.text


def test_an_offer_calls_its_rank_a_cost_where_lower_is_better(library, state):
    """The paper's 'reliability' is a cost (distance + alpha x action variance): printed as
    "reliability 0.391" at the prompt and on the page, it read as higher is better."""
    text = library.decide(GoalPoint((0.45, 0.5)), state).text
    assert "reliability" not in text
    assert re.search(r"; cost \d\.\d{3} = distance \+ 0\.5 x variance of its neighbours' "
                     r"actions, lower is better\)$", text), text


def test_goal_picks_a_learner_movement_and_says_which(library, state):
    action = np.full(A, -0.3)
    # A consistent neighbourhood of learner movements right at the goal.
    for k, dy in enumerate([0.0, 0.01, -0.01], start=7):
        state.add_movement(k, True, action, [-0.2 + dy, -0.2])
    demo = library.decide(GoalPoint((-0.2, -0.2)), state)
    assert demo.teaching_set_index == -1
    assert np.array_equal(demo.action, action)
    assert demo.outcome.tolist() == [-0.2, -0.2]  # that pair's own outcome, not the goal
    assert "learner movement 7" in demo.text


def test_goal_prefers_a_consistent_neighbourhood_over_the_nearest_point(state):
    """Reliability = distance + alpha * variance: the nearest pair sits among wildly different
    actions, a slightly farther one among identical actions."""
    rng = np.random.default_rng(3)
    outcomes = np.array([[0.0, 0.0], [0.02, 0.0], [-0.02, 0.0],  # noisy cluster at the goal
                         [0.3, 0.0], [0.31, 0.0], [0.29, 0.0]])  # consistent cluster
    actions = np.vstack([rng.uniform(-1, 1, (3, A)), np.tile(np.full(A, 0.5), (3, 1))])
    lib = TeachingLibrary(actions, outcomes, tolerance=0.05, config=LearnerConfig(k_max=3))
    # Goal 0.13 from the noisy pair (0.02, 0), 0.14 from the consistent (0.29, 0).
    demo = lib.decide(GoalPoint((0.15, 0.0)), state)
    assert demo.teaching_set_index == 5
    assert lib.decide(GoalPoint((0.03, 0.0)), state).teaching_set_index == 1  # close enough


# --- yaml files ----------------------------------------------------------------------------


def _write(tmp_path, text: str, name: str = "demo.yaml") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_yaml_list_and_mapping(tmp_path, library, state):
    values = [round(-1 + 2 * i / 23, 3) for i in range(A)]
    path = _write(tmp_path, str(values))
    decision = library.decide(YamlFile(path), state)
    assert isinstance(decision, ExecuteFirst) and decision.file_outcome is None
    assert decision.action.tolist() == values
    path = _write(tmp_path, f"action: {values}\noutcome: [0.2, -0.3]\n", "m.yaml")
    action, outcome = load_action_file(path, A)
    assert action.tolist() == values and outcome.tolist() == [0.2, -0.3]
    # PyYAML reads 1e-3 (no dot) as a string: accepted as the number it means.
    action, _ = load_action_file(_write(tmp_path, "[" + ", ".join(["1e-3"] * A) + "]"), A)
    assert action.tolist() == [0.001] * A


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("[0.1, 0.2]", ["action has 2 values, 24 are needed"]),
        ("action: [0.1]", ["action has 1 values"]),
        ("0.5", ["must hold a list of 24 numbers", "float"]),
        ("", ["must hold a list", "NoneType"]),
        ("hello", ["must hold a list", "str"]),
        ("outcome: [0.1, 0.2]", ["no 'action' key"]),
        ("action: [0.0]\noutcom: [0.1, 0.2]", ["unknown keys ['outcom']"]),
        ("action: 0.3", ["action must be a list of 24 numbers, not float"]),
        ("[" + ", ".join(["0.0"] * 23 + ["abc"]) + "]", ["action[23] is 'abc', not a number"]),
        ("[" + ", ".join(["0.0"] * 23 + [".nan"]) + "]", ["action[23] is NaN"]),
        ("[" + ", ".join(["0.0"] * 23 + [".inf"]) + "]", ["action[23] is infinite"]),
        ("[" + ", ".join(["1.5"] + ["0.0"] * 23) + "]", ["action[0] = 1.5 is outside [-1, 1]"]),
        ("[" + ", ".join(["true"] + ["0.0"] * 23) + "]", ["action[0] is True, not a number"]),
        ("[" + ", ".join(["[0.1]"] + ["0.0"] * 23) + "]", ["action[0] is [0.1], not a number"]),
        ("action: [" + ", ".join(["0.0"] * 24) + "]\noutcome: [0.1]", ["outcome has 1 values"]),
        ("action: [" + ", ".join(["0.0"] * 24) + "]\noutcome: [2, 0]", ["outcome[0] = 2"]),
        ("[0.1, 0.2", ["is not valid YAML (line"]),
    ],
)
def test_yaml_of_the_wrong_shape(tmp_path, library, state, text, words):
    path = _write(tmp_path, text)
    with pytest.raises(CommandError) as error:
        library.decide(YamlFile(path), state)
    for w in words:
        assert w in str(error.value)
    assert path in str(error.value)


def test_yaml_missing_file_and_directory(tmp_path, library, state):
    with pytest.raises(CommandError, match=r"no such file: .*nope\.yaml"):
        library.decide(YamlFile(str(tmp_path / "nope.yaml")), state)
    with pytest.raises(CommandError, match="is a directory"):
        library.decide(YamlFile(str(tmp_path)), state)
    binary = tmp_path / "b.yaml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(CommandError, match="cannot read"):
        library.decide(YamlFile(str(binary)), state)


def test_yaml_outcome_comes_from_execution_or_the_file_as_fallback():
    action = np.zeros(A)
    request = ExecuteFirst(action, None, "d.yaml")
    demo = executed_demonstration(request, True, [0.25, -0.5], "")
    assert demo.outcome.tolist() == [0.25, -0.5] and demo.teaching_set_index == -1
    assert "executed" in demo.text
    with pytest.raises(CommandError, match=r"did not land .*no contact.*nothing sent"):
        executed_demonstration(request, False, [], "no contact")
    with pytest.raises(CommandError, match="start sim_bridge, or add 'outcome"):
        unexecuted_demonstration(request, "execute_action is not available")
    with_file = ExecuteFirst(action, np.array([0.1, 0.1]), "d.yaml")
    demo = unexecuted_demonstration(with_file, "execute_action is not available")
    assert demo.outcome.tolist() == [0.1, 0.1] and "not executed" in demo.text
    demo = executed_demonstration(with_file, True, [0.1, 0.2], "")
    assert demo.outcome.tolist() == [0.1, 0.2] and "0.100 away and was not used" in demo.text
