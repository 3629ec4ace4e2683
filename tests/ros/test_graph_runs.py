"""End to end: every learner through the node graph, checked from its bag and against the
single-process runner.

The runs use the default processes (the message-only nodes share one), one learner also a
process per node; ``SGIM_TEST_SEPARATE=1`` runs every one of them a process per node, to check
the other layout whole (``SGIM_TEST_SEPARATE=1 ./test.sh tests/ros/test_graph_runs.py``)."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys

import numpy as np
import pytest

from sgim_nodes.core.config import LearnerConfig
from tests.conftest import REPO
from tests.golden_runs import (
    DIGESTS,
    EVAL_EVERY,
    MOVEMENTS,
    PERIOD,
    SEED,
    TOLERANCE,
    bag_digest,
    runner_digest,
    runner_records_later,
)

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
IMITATIONS = LearnerConfig().imitation_count


def run_graph(ros_processes, ros_domain, tmp_path, learner, *extra, timeout=300, seed=SEED,
              eval_every=EVAL_EVERY, markers=False):
    """The reference run of `learner` through the graph (tests/golden_runs.py), started.

    `eval_every` 0 for a test that checks no evaluation: only the first and the last are made
    (the evaluator casts in a world of its own, so the movements stay the same). `markers`:
    the whole graph, the markers node too, for the runs of each learner as a user starts them;
    the others leave it out (it only listens; tests/ros/test_markers.py checks its topics)."""
    if not markers:
        extra = ("--no-markers", *extra)
    if os.environ.get("SGIM_TEST_SEPARATE") == "1" and "--separate" not in extra:
        extra = ("--separate", *extra)
    child = ros_processes.start(
        f"run-{learner}",
        [RUN, learner, "--seed", str(seed), "--movements", str(MOVEMENTS), "--eval-every",
         str(eval_every), "--demonstration-period", str(PERIOD), "--runs-dir", str(tmp_path),
         "--name", learner, "--domain", str(ros_domain), "--quiet", "--timeout", str(timeout),
         *extra],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return child


def finish(child, tmp_path, learner, timeout=330):
    output, _ = child.communicate(timeout=timeout)
    assert child.returncode == 0, output[-3000:]
    from sgim_nodes.bag.reader import load_run

    return load_run(tmp_path / learner / "bag")


# The runs are tests/golden_runs.py's. sgim-d runs with a lenient teacher (the default rule,
# "ability": the learner's inverse model cast for a goal in the teacher's own world lands
# within 8 noise units of it): at some turns every teaching goal is within reach and the
# teacher shows nothing. Its turns without a demonstration, and the teacher's casts in its own
# world, must still match the runner (runner_records_later: beside the graph run).


def assert_the_teachers_checks(run, records, teacher_turns=()) -> None:
    """Issue 31: every turn of the automatic teacher is in the bag's teacher_checks, one check
    per teaching goal, and is redone from them alone (with the run's seed, RunStatus.seed): the
    entry its Demonstration shows, or its silence; and they are the runner's checks, number for
    number (the teacher's casts in its own world included)."""
    from sgim_nodes.bag.teacher_audit import redo

    audited = redo(run.teacher_checks, run.run_status[0].seed, teacher_turns)
    demos = [d for d in run.demonstrations if d.source == "automatic"]
    assert [(t.movement_index, t.help_request) for t in audited] == [
        (d.movement_index, d.help_request) for d in demos]
    for turn, demo in zip(audited, demos, strict=True):
        assert turn.verdicts_hold, turn.movement_index
        assert turn.drawn == demo.teaching_set_index, turn.movement_index  # -1: silent
        assert list(turn.marked) == [i for i in [demo.teaching_set_index] if i >= 0]
    expected = [r for r in records if r["type"] == "teacher_check"]
    assert len(run.teacher_checks) == len(expected) > 0

    def vec(values) -> np.ndarray:
        return np.asarray([] if values is None else values, dtype=float)

    for got, want in zip(run.teacher_checks, expected, strict=True):
        where = (got.movement_index, got.teaching_set_index)
        assert (got.movement_index, got.help_request, got.teaching_set_index, got.rule,
                got.choice, got.entries, got.status, got.own_outcomes, got.reached,
                got.chosen) == (want["movement"], want["help_request"], want["teaching_index"],
                                want["rule"], want["choice"], want["entries"], want["status"],
                                want["own_outcomes"], want["reached"], want["chosen"]), where
        for name in ("asked_goal", "goal", "action", "landed"):
            assert np.array_equal(getattr(got, name), vec(want[name])), (name, where)
        assert got.distance == (np.inf if want["distance"] is None else want["distance"])
        assert got.tolerance == want["tolerance"], where


def test_teachers_taking_turns_through_the_graph(ros_processes, ros_domain, tmp_path):
    """Issue 33's SGIM-D arm: SGIM-ACTS's three teachers take the automatic teacher's turns,
    each judging and showing its own part of the teaching set, rough its perturbed cast (a
    means-only demonstration when it lands nowhere); the graph is the runner's run, and every
    turn is redone from its checks with that turn's teacher's stream."""
    from sgim_nodes.core.teacher_turns import turn_specs

    names = ("centre", "west", "rough")
    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-d", "--param",
                      f"tolerance_noise={TOLERANCE['sgim-d']}", "--param",
                      f"teacher_turns={','.join(names)}", eval_every=0)
    later = runner_records_later("sgim-d", eval_every=0,
                                 teacher_turns=turn_specs("fishing", ",".join(names)))
    run = finish(child, tmp_path, "sgim-d")
    records = later.result()
    assert bag_digest(run.movements) == runner_digest(records) != DIGESTS["sgim-d"]
    shown = [r for r in records if r["type"] == "demonstration"]
    assert [r["teacher"] for r in shown][:3] == list(names)  # the first turns show
    demos = [d for d in run.demonstrations if len(d.action)]
    assert [(d.movement_index, d.teaching_set_index) for d in demos] == [
        (r["movement"], r["teaching_index"]) for r in shown]
    assert [d.content for d in demos] == [
        "means-only" if r["outcome"] is None else "means-and-goal" for r in shown]
    assert_the_teachers_checks(run, records, names)


def test_the_teachers_choice_rule_through_the_graph(ros_processes, ros_domain, tmp_path):
    """teacher_choice (issue 14) as a node parameter: the graph's teacher demonstrates the
    same goals as the runner's with the same rule, and the learner makes the same movements."""
    choice, seed = "farthest-unreached", 1  # seed 1: 3 entries shown, others than by default
    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-d", "--param",
                      f"tolerance_noise={TOLERANCE['sgim-d']}", "--param",
                      f"teacher_choice={choice}", seed=seed, eval_every=0)
    later = runner_records_later("sgim-d", seed=seed, eval_every=0, teacher_choice=choice)
    by_default = runner_records_later("sgim-d", seed=seed, eval_every=0)
    run = finish(child, tmp_path, "sgim-d")
    records = later.result()
    shown = [d.teaching_set_index for d in run.demonstrations if len(d.action)]
    expected = [r["teaching_index"] for r in records if r["type"] == "demonstration"]
    assert shown == expected and len(shown) >= 3
    default = [r["teaching_index"] for r in by_default.result()
               if r["type"] == "demonstration"]
    assert default != expected  # the rule changed what was taught
    assert_the_teachers_checks(run, records)
    moves = [r for r in records if r["type"] == "movement"]
    for graph_move, move in zip(run.movements, moves, strict=True):
        assert np.array_equal(graph_move.action, np.asarray(move["action"])), graph_move.index


def test_the_own_movements_rule_s_checks_through_the_graph(ros_processes, ros_domain,
                                                           tmp_path):
    """reached_rule own-movements (issue 31): no cast; each check names the learner's own
    outcome nearest its goal, which an auditor finds again among the bag's movements before
    the turn (goal-directed, exploration or random, with an outcome); the checks are the
    runner's and redo every turn, the silent ones (most, with this lenient tolerance) too."""
    from sgim_msgs.msg import Movement

    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-d", "--param",
                      f"tolerance_noise={TOLERANCE['sgim-d']}", "--param",
                      "reached_rule=own-movements", eval_every=0)
    later = runner_records_later("sgim-d", eval_every=0, reached_rule="own-movements")
    run = finish(child, tmp_path, "sgim-d")
    records = later.result()
    moves = [r for r in records if r["type"] == "movement"]
    for graph_move, move in zip(run.movements, moves, strict=True):
        assert np.array_equal(graph_move.action, np.asarray(move["action"])), graph_move.index
    assert_the_teachers_checks(run, records)
    own = {Movement.PROCESS_GOAL_DIRECTED, Movement.PROCESS_EXPLORATION, Movement.PROCESS_RANDOM}
    for check in run.teacher_checks:
        assert check.rule == "own-movements" and len(check.action) == 0
        outcomes = np.array([m.outcome for m in run.movements
                             if m.index <= check.movement_index and m.process in own
                             and m.status == Movement.STATUS_OK]).reshape(-1, 2)
        assert check.own_outcomes == len(outcomes)
        if len(outcomes) == 0:
            assert len(check.landed) == 0 and check.distance == np.inf
            continue
        gaps = np.linalg.norm(outcomes - check.goal, axis=1)
        assert check.distance == pytest.approx(gaps.min(), rel=1e-12, abs=0)
        assert any(np.array_equal(check.landed, y) for y in outcomes[gaps == gaps.min()])


def social_mode_run(ros_processes, ros_domain, tmp_path, name, seed=SEED, **teacher):
    """sgim-d through the graph with `teacher` (social modes as --param NAME=VALUE), and the
    runner's records for the same settings; the graph's movements must be the runner's."""
    params = [f"tolerance_noise={TOLERANCE['sgim-d']}",
              *(f"{key}={value}" for key, value in teacher.items())]
    child = run_graph(ros_processes, ros_domain, tmp_path / name, "sgim-d",
                      *itertools.chain.from_iterable(("--param", p) for p in params), seed=seed)
    later = runner_records_later("sgim-d", seed=seed, **teacher)
    run = finish(child, tmp_path / name, "sgim-d")
    records = later.result()
    moves = [r for r in records if r["type"] == "movement"]
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    for graph_move, move in zip(run.movements, moves, strict=True):
        assert np.array_equal(graph_move.action, np.asarray(move["action"])), graph_move.index
    evaluations = [r["mean_distance"] for r in records if r["type"] == "evaluation"]
    assert [e.mean_distance for e in run.evaluations] == pytest.approx(evaluations, abs=1e-12)
    assert_the_teachers_checks(run, records)
    shown = [(d.movement_index, d.teaching_set_index) for d in run.demonstrations if d.shown]
    expected = [(r["movement"], r["teaching_index"]) for r in records
                if r["type"] == "demonstration"]
    assert shown == expected and len(shown) >= 3
    return run, records


def test_goal_only_demonstrations_through_the_graph(ros_processes, ros_domain, tmp_path):
    """demonstration_content goal-only (issue 14, emulation): the learner is shown the outcome
    only, adopts it as its next goal and reaches for it with its own inverse model; no
    demonstrated action reaches it, its memory or the bag; movements equal the runner's."""
    from sgim_msgs.msg import Goal, Movement
    from sgim_nodes.bag.rebuild import rebuild_from_records
    from sim_bridge.data_files import load_teaching_set

    run, _ = social_mode_run(ros_processes, ros_domain, tmp_path, "goal",
                             demonstration_content="goal-only")
    teaching = load_teaching_set()
    demos = [d for d in run.demonstrations if d.shown]
    for demo in [*demos, *run.demonstrations_taken]:
        assert demo.content == "goal-only" and len(demo.action) == 0
        assert np.array_equal(demo.outcome, teaching.outcomes[demo.teaching_set_index])
    assert [d.movement_index for d in run.demonstrations_taken] == [
        d.movement_index for d in demos]
    # Each one is adopted as a goal at once (Goal mode 4), and that goal attempt is the
    # learner's own: goal-directed or exploration movements aimed at it, never an imitation.
    for demo in demos:
        goal = next(g for g in run.goals if g.movement_index == demo.movement_index)
        assert goal.mode == Goal.MODE_DEMONSTRATION
        assert np.array_equal(goal.point, demo.outcome)
        first = run.movements[demo.movement_index]
        assert first.goal_index == goal.index and np.array_equal(first.goal, demo.outcome)
        attempt = next(c for c in run.competences if c.goal_index == goal.index)
        assert attempt.from_demonstration
    assert Movement.PROCESS_IMITATION not in {m.process for m in run.movements}
    # No action the teacher could have shown was ever cast or stored.
    shown_actions = teaching.actions[[d.teaching_set_index for d in demos]]
    for move in run.movements:
        assert not any(np.array_equal(move.action, a) for a in shown_actions)
    state = rebuild_from_records(run)
    assert state.n_demonstrations == 0 and "demonstration" not in state.memory.labels


def test_means_only_demonstrations_through_the_graph(ros_processes, ros_domain, tmp_path):
    """demonstration_content means-only: the learner is shown the action only, imitates it and
    learns where it lands from its own casts; the teacher's outcome never reaches it, its
    memory or the bag, and it records no competence for a goal it was never given."""
    from sgim_msgs.msg import Goal, Movement
    from sgim_nodes.bag.rebuild import rebuild_from_records
    from sim_bridge.data_files import load_teaching_set

    # Seed 2: its learner leaves teaching goals unreached at 3 of the teacher's turns, so
    # imitations are seen 3 times (seeds are chosen for what they show: they change with the
    # learner).
    run, _ = social_mode_run(ros_processes, ros_domain, tmp_path, "means", seed=2,
                             demonstration_content="means-only")
    teaching = load_teaching_set()
    demos = [d for d in run.demonstrations if d.shown]
    for demo in [*demos, *run.demonstrations_taken]:
        assert demo.content == "means-only" and len(demo.outcome) == 0
        assert np.array_equal(demo.action, teaching.actions[demo.teaching_set_index])
    for demo in demos:  # imitated at once, aiming at no goal
        k = demo.movement_index
        follow = run.movements[k: k + IMITATIONS]
        assert all(m.process == Movement.PROCESS_IMITATION and len(m.goal) == 0
                   for m in follow), k
        assert all(np.linalg.norm(m.action - demo.action) < LearnerConfig().imitation_epsilon
                   for m in follow)
    assert not any(c.from_demonstration for c in run.competences)
    assert Goal.MODE_DEMONSTRATION not in {g.mode for g in run.goals}
    # What memory holds of the demonstrations is the learner's own casts: no pair labelled a
    # demonstration, no teaching outcome anywhere in the bag.
    state = rebuild_from_records(run)
    assert state.n_demonstrations == 0 and "demonstration" not in state.memory.labels
    imitations = [m for m in run.movements if m.process == Movement.PROCESS_IMITATION]
    assert state.memory.labels.count("imitation") == sum(len(m.outcome) > 0
                                                          for m in imitations)
    shown_outcomes = teaching.outcomes[[d.teaching_set_index for d in demos]]
    for outcome in state.memory.outcomes:
        assert not any(np.array_equal(outcome, y) for y in shown_outcomes)


def test_on_request_timing_through_the_graph(ros_processes, ros_domain, tmp_path):
    """timing on-request: the arbiter asks on help_requests when the core's rule says so, the
    teacher answers each ask on demonstrations (naming it), both recorded; the asks, the
    answers and every movement are the runner's, unanswered asks included. Seed 2 (runner:
    asks at movements 30, 65, 102, 162, 200 and 250): the asks at 162, mid-attempt, and 250
    find the teacher with nothing to show, and an ask ends the attempt under way whether
    answered or not, in the runner as in the graph (the arbiter had to stop its job to ask).
    Seeds are chosen for what they show: they change with the learner."""
    from sgim_msgs.msg import Movement

    run, records = social_mode_run(ros_processes, ros_domain, tmp_path, "asks", seed=2,
                                   timing="on-request")
    asks = [(r["movement"], r["goal"]) for r in records if r["type"] == "help_request"]
    assert [(h.index, h.movement_index) for h in run.help_requests] == [
        (i, k) for i, (k, _) in enumerate(asks, 1)]
    for ask, (_, goal) in zip(run.help_requests, asks, strict=True):
        assert np.array_equal(ask.goal, np.asarray(goal))
    # One answer per ask, at its count; the teacher speaks at no other time.
    answers = run.demonstrations
    assert [(d.help_request, d.movement_index) for d in answers] == [
        (h.index, h.movement_index) for h in run.help_requests]
    assert any(not d.shown for d in answers), "an unanswered ask is part of what is tested"
    budget = len(range(0, MOVEMENTS, PERIOD))
    assert len(run.help_requests) <= budget
    assert all(h.index <= h.movement_index // PERIOD + 1 for h in run.help_requests)
    for demo in (d for d in answers if d.shown):  # shown both parts, imitated at once
        assert len(demo.action) and len(demo.outcome)
        k = demo.movement_index
        assert all(m.process == Movement.PROCESS_IMITATION
                   for m in run.movements[k: k + IMITATIONS])


def test_where_reach_goal_jobs_end_changes_no_movement(ros_processes, ros_domain, tmp_path):
    """A reach_goal job spans goals up to the arbiter's next boundary; with two goals per job
    the jobs end at other goal boundaries than the default's, and the run is still the
    runner's, movement for movement (the explorer's choose_goal waits for every competence)."""
    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-d", "--param",
                      f"tolerance_noise={TOLERANCE['sgim-d']}", "--param", "goals_per_job=2",
                      eval_every=0)
    later = runner_records_later("sgim-d", eval_every=0)
    run = finish(child, tmp_path, "sgim-d")
    moves = [r for r in later.result() if r["type"] == "movement"]
    assert len(run.movements) == len(moves) == MOVEMENTS
    for graph_move, move in zip(run.movements, moves, strict=True):
        assert np.array_equal(graph_move.action, np.asarray(move["action"])), graph_move.index
    # Every goal drawn was attempted: no job chose a goal it then did not reach for.
    assert {g.index for g in run.goals} == {c.goal_index for c in run.competences
                                            if c.goal_index}


# Each learner through the default processes (the message-only nodes share one), one also
# with a process per node (--separate): both make the runner's movements.
@pytest.mark.parametrize("learner, separate", [("sgim-d", False), ("saggriac", False),
                                               ("random-goals", True), ("demo-only", False),
                                               ("random", False)])
def test_learner_through_the_graph(ros_processes, ros_domain, tmp_path, learner, separate):
    from sgim_msgs.msg import Movement, RunStatus
    from sgim_nodes.graph.processes import node_log

    extra = ["--param", f"tolerance_noise={TOLERANCE[learner]}"] if learner in TOLERANCE else []
    separate = separate or os.environ.get("SGIM_TEST_SEPARATE") == "1"
    layout = ["--separate"] if separate else []
    child = run_graph(ros_processes, ros_domain, tmp_path, learner, *extra, *layout,
                      markers=True)
    later = runner_records_later(learner)
    run = finish(child, tmp_path, learner)
    logs = tmp_path / learner / "logs"
    if separate:  # every node its own process and log
        assert not (logs / "chain.log").exists()
        assert not list(logs.glob("*.nodes"))
    else:  # the arbiter and the recorder ended by themselves while their process went on
        assert node_log(logs, "recorder") == logs / "observers.log"
        for node in ("social_interaction", "recorder"):
            log = node_log(logs, node)
            if log.stem != node:  # in a shared process (the random learner's arbiter is alone)
                assert f"[{log.stem}] {node} ended (exit 0)" in log.read_text()

    # Every movement recorded once, in order.
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    processes = [m.process for m in run.movements]
    # Movement.msg: evaluation casts and a teacher's measuring casts are never published.
    assert not {Movement.PROCESS_EVALUATION, Movement.PROCESS_DEMONSTRATION} & set(processes)
    # Evaluations at the right counts, and the run's end recorded.
    assert [e.movement_index for e in run.evaluations] == [0, 100, 200, 300]
    assert all(len(e.distances) == len(run.evaluations[0].distances) > 50
               for e in run.evaluations)
    assert run.run_status[-1].state == RunStatus.STATE_FINISHED
    # RunStatus as its message file says: "started", then at the first goal's end or job
    # boundary after every further 5 % of the budget, "movement budget spent" and "finished".
    statuses = run.run_status
    assert (statuses[0].message, statuses[0].movement_index) == ("started", 0)
    assert [s.message for s in statuses[-2:]] == ["movement budget spent", "finished"]
    progress = [s.movement_index for s in statuses
                if s.state == RunStatus.STATE_RUNNING and not s.message]
    assert progress[-1] == MOVEMENTS and len(progress) <= 21, progress  # the last: spent
    assert all(b - a >= MOVEMENTS // 20 for a, b in itertools.pairwise(progress[:-1])), \
        progress

    if learner in ("sgim-d", "saggriac", "random-goals"):
        maps = run.region_map
        counts = [m.goal_count for m in maps]
        assert counts == sorted(counts) and counts[-1] == len(run.competences) > 10
        assert len(run.goals) >= len(run.competences) - len(run.demonstrations)
        # The goal generator folds the competences into its own tree: each goal's region is
        # the leaf holding it in the interest computer's map of the goals folded before it.
        by_count = {m.goal_count: m for m in maps}
        checked = 0
        for goal in run.goals:
            folded = sum(c.movement_index <= goal.movement_index for c in run.competences)
            if folded in by_count:
                leaf = next(r for r in by_count[folded].leaves
                            if np.all(goal.point >= r.lower) and np.all(goal.point <= r.upper))
                assert goal.region_id == leaf.id, goal.index
                checked += 1
        assert checked > len(run.goals) // 2, (checked, len(run.goals))
    if learner in ("sgim-d", "demo-only"):
        demos = [d for d in run.demonstrations if len(d.action)]
        assert [d.movement_index for d in run.demonstrations] == list(range(0, MOVEMENTS,
                                                                           PERIOD))
        if learner == "sgim-d":  # the lenient teacher had nothing to show at some turn
            assert 0 < len(demos) < len(run.demonstrations)
        assert demos and all(d.source == "automatic" for d in demos)
        for demo in demos:  # each demonstration is followed by its imitation at once
            k = demo.movement_index
            follow = run.movements[k: k + (IMITATIONS if learner == "sgim-d" else PERIOD)]
            assert all(m.process == Movement.PROCESS_IMITATION for m in follow), k
            assert all(np.allclose(m.goal, demo.outcome) for m in follow)
            assert all(np.linalg.norm(m.action - demo.action) < LearnerConfig().imitation_epsilon
                       for m in follow)
    if learner == "saggriac":
        assert Movement.PROCESS_IMITATION not in processes
        assert set(processes) <= {Movement.PROCESS_GOAL_DIRECTED, Movement.PROCESS_EXPLORATION}
    if learner == "random":
        assert set(processes) == {Movement.PROCESS_RANDOM}

    # The graph is the single-process learner, movement for movement, and both make the
    # reference run of every machine (tests/golden_runs.py, core/portable.py).
    records = later.result()
    moves = [r for r in records if r["type"] == "movement"]
    assert len(moves) == MOVEMENTS
    assert bag_digest(run.movements) == runner_digest(records) == DIGESTS[learner]
    for graph_move, move in zip(run.movements, moves, strict=True):
        assert np.array_equal(graph_move.action, np.asarray(move["action"])), graph_move.index
    evaluations = [r["mean_distance"] for r in records if r["type"] == "evaluation"]
    assert [e.mean_distance for e in run.evaluations] == pytest.approx(evaluations, abs=1e-12)
    if learner in ("sgim-d", "demo-only"):  # the automatic teacher's turns, silent ones too
        assert_the_teachers_checks(run, records)
    else:
        assert run.teacher_checks == []


def test_sgim_acts_through_the_graph(ros_processes, ros_domain, tmp_path):
    """Issue 33: SGIM-ACTS's graph (its three experts in their namespaces) is the runner's
    learner: the same movements, the same requests to the same teachers, the same answers and
    the same competence per (strategy, goal)."""
    from sgim_msgs.msg import Goal

    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-acts", markers=True)
    later = runner_records_later("sgim-acts")
    run = finish(child, tmp_path, "sgim-acts")
    records = later.result()
    assert bag_digest(run.movements) == runner_digest(records) == DIGESTS["sgim-acts"]
    evaluations = [r["mean_distance"] for r in records if r["type"] == "evaluation"]
    assert [e.mean_distance for e in run.evaluations] == pytest.approx(evaluations, abs=1e-12)

    # Every request: when, to whom, for what, about which goal (1-based in the graph).
    requests = [r for r in records if r["type"] == "request"]
    assert len(requests) == len(run.help_requests) > 5
    for ask, want in zip(run.help_requests, requests, strict=True):
        assert ask.index == want["request"] + 1 and ask.movement_index == want["movement"]
        assert f"{'mimicry' if ask.content == 'means-and-goal' else 'emulation'}:" \
               f"{ask.teacher}" == want["strategy"]
        assert np.array_equal(ask.goal, want["goal"])
    # Every answer: from the expert asked, its world row, or "none there" (empty).
    answers = {r["request"] + 1: r for r in records if r["type"] == "answer"}
    replies = [d for d in run.demonstrations if d.help_request]
    assert sorted(d.help_request for d in replies) == sorted(answers)
    for reply in replies:
        want = answers[reply.help_request]
        assert reply.source == f"expert:{want['teacher']}"
        shown = len(reply.action) or len(reply.outcome)
        assert bool(shown) == (want["answered"] and (want["action"] is not None
                                                    or want["outcome"] is not None))
        if shown:
            assert reply.teaching_set_index == want["teaching_index"]
    # Each ended episode's competence, at its chosen goal, in its strategy's history.
    ended = [r for r in records if r["type"] == "strategy_choice" and r["competence"] is not None]
    assert [c.strategy for c in run.competences] == [r["strategy"] for r in ended]
    assert [c.competence for c in run.competences] == pytest.approx(
        [r["competence"] for r in ended], abs=1e-12)
    for comp, want in zip(run.competences, ended, strict=True):
        assert np.array_equal(comp.goal, want["goal"])
    assert {g.strategy for g in run.goals} >= {"autonomous"}
    assert all(g.mode != Goal.MODE_DEMONSTRATION for g in run.goals)
    assert run.teacher_checks == []


def test_a_demonstration_mid_goal_is_handled_at_the_next_movement_boundary(
        ros_processes, ros_domain, tmp_path, rclpy_context):
    from rclpy.duration import Duration

    from sgim_msgs.msg import Demonstration, Movement
    from sgim_ros import qos
    from sim_bridge.data_files import load_teaching_set
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "demo_injector")
    seen: list[Movement] = client.capture(Movement, "/movements", qos.RECORDS)
    publisher = client.node.create_publisher(Demonstration, "/demonstrations", qos.RECORDS)
    child = run_graph(ros_processes, ros_domain, tmp_path, "sgim-d", "--teacher", "external")
    teaching = load_teaching_set()
    # Wait until a goal attempt is under way (a goal-directed movement past the first ones)
    # and the arbiter and the recorder hear the demonstration (as tests/ros/test_faults.py).
    assert client.spin_until(
        lambda: len(seen) > 40 and seen[-1].process == Movement.PROCESS_GOAL_DIRECTED
        and publisher.get_subscription_count() >= 2, timeout=120)
    sent_after = seen[-1].index
    from sgim_ros.record_key import read_key, sign_teaching

    key = read_key(tmp_path / "sgim-d")  # an external teacher signs with the run's key
    assert key
    publisher.publish(sign_teaching("demonstrations", Demonstration(
        index=1, movement_index=sent_after, action=teaching.actions[0].tolist(),
        outcome=teaching.outcomes[0].tolist(), teaching_set_index=0, source="human"), key))
    # Closing before every reader acknowledged it could lose it (seen once under load: the
    # run went on without a demonstration).
    assert publisher.wait_for_all_acked(Duration(seconds=30))
    client.close()
    run = finish(child, tmp_path, "sgim-d")

    imitation = [m.index for m in run.movements if m.process == Movement.PROCESS_IMITATION]
    assert len(imitation) == IMITATIONS
    first = imitation[0]
    # The learner took it when the cut job reported back, and imitated at once.
    assert [d.movement_index + 1 for d in run.demonstrations_taken] == [first]
    # The movement under way, then message latency: the demonstration reaches the arbiter,
    # whose cancel reaches the explorer's job, two hops that took up to 3 movements on a
    # loaded machine (load 5.5 on 2 cores), more under heavier load. A job that ignored the
    # cancel would go on to its cap: goals_per_job (50) goals, hundreds of movements.
    assert sent_after < first <= sent_after + 10, (sent_after, first)
    assert imitation == list(range(first, first + IMITATIONS))
    # The interrupted goal still counted for the interest, and the demonstrated goal too.
    assert any(c.from_demonstration for c in run.competences)
    interrupted = [c for c in run.competences if c.movement_index == first - 1]
    assert interrupted and interrupted[0].movements_used >= 1


def test_the_human_teacher_script_drives_a_run_through_the_prompt(
        ros_processes, ros_domain, tmp_path):
    import re
    import threading
    import time

    from sgim_msgs.msg import Movement

    child = ros_processes.start(
        "human-run",
        [RUN, "sgim-d", "--seed", "1", "--movements", "600", "--eval-every", "0",
         "--runs-dir", str(tmp_path), "--name", "human", "--domain", str(ros_domain),
         "--teacher", "human", "--quiet", "--timeout", "240"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(child.stdout), daemon=True)
    reader.start()
    child.stdin.write("teach 999\n")  # bad input: a message and a new prompt
    child.stdin.flush()
    deadline = time.monotonic() + 120
    # A person teaches a running learner: wait until the prompt shows movements.
    while not any(re.search(r"movements [1-9]", line) for line in lines):
        assert time.monotonic() < deadline, "".join(lines)[-3000:]
        child.stdin.write("status\n")
        child.stdin.flush()
        time.sleep(0.5)
    while not any("sent demonstration" in line for line in lines):
        assert time.monotonic() < deadline, "".join(lines)[-3000:]
        child.stdin.write("teach 0\n")  # refused until the learner listens
        child.stdin.flush()
        time.sleep(1.0)
    child.stdin.write("quit\n")
    child.stdin.close()
    assert child.wait(timeout=300) == 0, "".join(lines)[-3000:]
    reader.join(timeout=10)
    output = "".join(lines)
    assert "999" in output and "error" in output.lower()
    from sgim_nodes.bag.reader import load_run

    run = load_run(tmp_path / "human" / "bag")
    assert [d.source for d in run.demonstrations] == ["human"]
    processes = [m.process for m in run.movements]
    assert processes.count(Movement.PROCESS_IMITATION) == IMITATIONS
    assert [m.index for m in run.movements] == list(range(1, 601))



def test_an_interrupted_sgim_acts_run_resumes_and_goes_on_asking(ros_processes, ros_domain,
                                                                 tmp_path):
    """SGIM-ACTS resumed: its goal generator rebuilds each strategy's history from the
    recorded competences, its requests go on numbering after the recorded ones, and the run
    reaches its budget with every answer naming its own request."""
    import signal
    import time

    import yaml

    from sgim_nodes.bag.resume import load_run_folder, segments
    from tests.ros.test_faults import recorded_movements

    movements, cut = 360, tmp_path / "cut"
    common = ["--domain", str(ros_domain), "--quiet", "--timeout", "600"]
    first = ros_processes.start("acts-cut", [
        RUN, "sgim-acts", "--seed", "3", "--movements", str(movements), "--eval-every", "120",
        "--runs-dir", str(tmp_path), "--name", "cut", *common],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    deadline = time.monotonic() + 300
    while recorded_movements(cut / "bag") < 60:
        assert time.monotonic() < deadline and first.poll() is None, "the run did not reach 60"
        time.sleep(0.3)
    first.send_signal(signal.SIGINT)
    output, _ = first.communicate(timeout=120)
    assert first.returncode == 130, output[-3000:]  # it had not finished
    asked_before = len(load_run_folder(cut).help_requests)

    second = ros_processes.start("acts-resumed", [RUN, "--resume", str(cut), *common],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = second.communicate(timeout=600)
    assert second.returncode == 0, output[-3000:]
    assert [p.name for p in segments(cut)] == ["bag", "bag.resume1"]
    run = load_run_folder(cut)
    assert [m.index for m in run.movements] == list(range(1, movements + 1))
    indices = [h.index for h in run.help_requests]
    assert len(indices) > asked_before > 0 and indices == sorted(set(indices))
    replies = [d.help_request for d in run.demonstrations if d.help_request]
    assert sorted(replies) == sorted(set(replies)) and set(replies) <= set(indices)
    assert {c.strategy for c in run.competences} >= {"autonomous"}
    meta = yaml.safe_load((cut / "metadata.yaml").read_text())
    assert meta["outcome"] == "finished" and len(meta["resumed"]) == 1
    assert meta["quarantine"]["total"] == 0, meta["quarantine"]


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-x", "-q"]))
