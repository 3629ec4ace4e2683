"""Rogue or late records in a bag (issue 12): every reader quarantines them by name, and rebuild
and resume fold exactly the run that happened."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import yaml

from sgim_nodes.bag.reader import BagReadWarning, QuarantineWarning, load_run
from sgim_nodes.bag.rebuild import main as rebuild_main
from sgim_nodes.bag.rebuild import rebuild
from sgim_nodes.bag.resume import resume_point
from sgim_nodes.core.config import LearnerConfig
from tests.bag import samples

N = 120
CONFIG = LearnerConfig(max_goals_per_region=6, zeta=4, min_goals_per_child=2)


@pytest.fixture(scope="module")
def clean():
    return samples.synthetic_run(N, seed=4)


def _after_movement(messages, k, extra):
    """`messages` with `extra` inserted right after movement k's record."""
    at = next(i for i, (t, m) in enumerate(messages) if t == "movements" and m.index == k)
    return [*messages[: at + 1], *extra, *messages[at + 1:]]


def _run_folder(tmp_path, messages, budget=N):
    run = tmp_path / "run"
    run.mkdir(parents=True)
    (run / "params.yaml").write_text(yaml.safe_dump({"/**": {"ros__parameters": {
        "movements": budget, "action_size": 24, "outcome_size": 2}}}))
    samples.write_bag(run / "bag", messages, chunk_messages=40)
    return run


def _state(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        state = rebuild(path, CONFIG)
    return state, [str(w.message) for w in caught if issubclass(w.category, QuarantineWarning)]


def _same_memory(a, b):
    return np.array_equal(a.memory.actions, b.memory.actions) and np.array_equal(
        a.memory.outcomes, b.memory.outcomes)


def _demo(rng, **fields):
    demo = samples.demonstration(9, 30, rng)
    for name, value in fields.items():
        setattr(demo, name, value)
    return demo


def test_invalid_demonstrations_are_quarantined_and_rebuild_and_resume_go_on(tmp_path, clean):
    rng = np.random.default_rng(1)
    rogues = [_demo(rng, action=np.full(24, np.nan)), _demo(rng, action=np.full(24, np.inf)),
              _demo(rng, action=np.zeros(5)), _demo(rng, outcome=np.array([1e300, -1e300])),
              _demo(rng, teaching_set_index=2**31 - 1), _demo(rng, teaching_set_index=-7)]
    # Each offered, and (as a forged arbiter record) "taken": both topics are checked.
    extra = [(topic, d) for d in rogues for topic in ("demonstrations", "demonstrations_taken")]
    run = _run_folder(tmp_path, _after_movement(clean, 30, extra))
    reference = _run_folder(tmp_path / "ref", clean)
    state, messages = _state(run)
    assert _same_memory(state, _state(reference)[0])
    kinds = [(q.topic, q.problem.kind) for q in state.quarantined]
    assert kinds.count(("demonstrations", "non-finite")) == 2
    assert ("demonstrations", "size") in kinds and ("demonstrations", "out-of-bounds") in kinds
    assert kinds.count(("demonstrations_taken", "unknown-teaching-index")) == 2
    assert len(kinds) == 12
    assert "demonstrations record 30 quarantined: demonstrated action has NaN" in messages[0]
    # resume reads the run folder the same way: every stateful node starts
    point = resume_point(run, CONFIG)
    assert point.count == N and _same_memory(point.state, state)


def test_forged_duplicates_never_replace_the_real_movements(tmp_path, clean):
    rng = np.random.default_rng(2)
    forged = [("movements", samples.movement(k, rng)) for k in (5, 6, 7)]
    # also after a rogue job and a cancel: movements 52-90 recorded again by another client
    rogue_job = [("movements", samples.movement(k, rng, process=1)) for k in range(52, 91)]
    messages = _after_movement(_after_movement(clean, 100, forged), 110, rogue_job)
    run = _run_folder(tmp_path, messages)
    state, lines = _state(run)
    reference, _ = _state(_run_folder(tmp_path / "ref", clean))
    assert _same_memory(state, reference) and state.missing == [] and state.duplicates == 0
    assert [q.index for q in state.quarantined] == [5, 6, 7, *range(52, 91)]
    assert {q.problem.kind for q in state.quarantined} == {"duplicate"}
    assert "simulator" not in " ".join(lines)  # nobody blames a restart that never happened
    assert "movement 5 again (attempt 0), not a re-execution" in lines[0]


def test_a_re_execution_supersedes_its_first_record_and_a_late_stale_one_is_refused(
        tmp_path, clean):
    rng = np.random.default_rng(3)
    redo = samples.movement(40, rng, attempt=1)
    stale = samples.movement(40, rng, attempt=1)  # the same attempt again: a duplicate
    forged_later = samples.movement(12, rng, attempt=3)  # not the latest movement
    run = _run_folder(tmp_path, _after_movement(
        clean, 40, [("movements", redo), ("movements", stale), ("movements", forged_later)]))
    with pytest.warns(BagReadWarning, match=r"movement\(s\) \[40\] re-executed"):
        records = load_run(run / "bag")
    assert [m.index for m in records.movements] == list(range(1, N + 1))
    assert np.array_equal(records.movements[39].action, redo.action)
    assert records.movements[39].attempt == 1 and records.superseded == [40]
    assert [(q.index, q.problem.kind) for q in records.quarantined] == [
        (40, "duplicate"), (12, "duplicate")]


@pytest.mark.parametrize("index", [2_000_000, int(1e9), N + 1])
def test_a_movement_index_far_ahead_is_quarantined_not_followed(tmp_path, clean, index):
    rng = np.random.default_rng(4)
    messages = _after_movement(clean, 20, [("movements", samples.movement(index, rng))])
    state, lines = _state(_run_folder(tmp_path, messages, budget=0 if index == N + 1 else N))
    assert state.n_movements == N and state.n_recorded == N and state.missing == []
    assert len(state.quarantined) == 1
    assert state.quarantined[0].problem.kind in ("jumps-ahead", "beyond-budget")
    assert str(index) in lines[0]


def test_nan_movements_published_ahead_of_the_simulator_do_not_hide_the_real_ones(
        tmp_path, clean):
    rng = np.random.default_rng(5)
    ahead = []
    for k in range(21, 51):
        bad = samples.movement(k, rng)
        bad.outcome = np.array([np.nan, np.nan])
        ahead.append(("movements", bad))
    state, _ = _state(_run_folder(tmp_path, _after_movement(clean, 20, ahead)))
    reference, _ = _state(_run_folder(tmp_path / "ref", clean))
    assert _same_memory(state, reference) and state.n_recorded == N
    assert len(state.quarantined) == 30
    assert {q.problem.kind for q in state.quarantined} == {"non-finite"}


def test_bad_competences_are_not_folded_and_rebuild_does_not_crash(tmp_path, clean):
    rng = np.random.default_rng(6)
    bad = []
    for goal, value in (([0.1, 0.1], np.nan), ([0.1, 0.1], -1e12), ([0.1, 0.2, 0.3], -0.5)):
        comp = samples.competence(3, 30, rng)
        comp.goal, comp.competence = np.asarray(goal), value
        bad.append(("competences", comp))
    state, _ = _state(_run_folder(tmp_path, _after_movement(clean, 30, bad)))
    reference, _ = _state(_run_folder(tmp_path / "ref", clean))
    assert state.n_competences == reference.n_competences
    assert sorted((tuple(r.low), tuple(r.high)) for r in state.tree.leaves) == sorted(
        (tuple(r.low), tuple(r.high)) for r in reference.tree.leaves)
    assert [q.problem.kind for q in state.quarantined] == ["non-finite", "out-of-bounds",
                                                           "size"]


def test_only_the_demonstrations_the_learner_took_enter_memory(tmp_path, clean):
    rng = np.random.default_rng(7)
    burst = [("demonstrations", samples.demonstration(k, 60, rng)) for k in range(2, 40)]
    state, _ = _state(_run_folder(tmp_path, _after_movement(clean, 60, burst)))
    reference, _ = _state(_run_folder(tmp_path / "ref", clean))
    assert _same_memory(state, reference) and state.n_demonstrations == 1


def test_a_late_demonstration_leaves_a_resumed_run_at_its_budget(tmp_path, clean):
    """`--teacher external`, a demonstration once the budget is spent: it is recorded, never
    taken, and the movements an imitation of it would make are beyond the budget. A resume
    starts at the budget exactly (it used to count past it and wait for an evaluation that
    never comes)."""
    rng = np.random.default_rng(8)
    late = [("demonstrations", samples.demonstration(2, N, rng)),
            *[("movements", samples.movement(k, rng, process=2)) for k in (N + 1, N + 2)]]
    run = _run_folder(tmp_path, [*clean[:-1], *late, clean[-1]])
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        point = resume_point(run, CONFIG)
        reference = resume_point(_run_folder(tmp_path / "ref", clean), CONFIG)
    assert point.count == N and _same_memory(point.state, reference.state)
    assert point.state.n_demonstrations == reference.state.n_demonstrations == 1
    assert [(q.index, q.problem.kind) for q in point.state.quarantined] == [
        (N + 1, "beyond-budget"), (N + 2, "beyond-budget")]


def test_rebuild_reads_a_run_folder_with_its_resumed_segments(tmp_path, clean, capsys):
    cut = next(i for i, (t, m) in enumerate(clean) if t == "movements" and m.index == 70)
    run = _run_folder(tmp_path, clean[: cut + 1])
    samples.write_bag(run / "bag.resume1", clean[cut + 1:])
    state, _ = _state(run)
    reference, _ = _state(_run_folder(tmp_path / "ref", clean))
    assert state.n_movements == N and _same_memory(state, reference)
    assert rebuild_main([str(run)]) == 0
    captured = capsys.readouterr()
    assert f"movements: {N} (learner count)" in captured.out
    assert "bag.resume1" in captured.err


def test_rebuild_names_what_a_path_is_when_it_is_no_bag(tmp_path, capsys):
    folder = tmp_path / "runs" / "x"
    folder.mkdir(parents=True)
    (folder / "metadata.yaml").write_text("learner: sgim-d\nseed: 0\n")  # a run's, no bag/
    assert rebuild_main([str(folder)]) == 2
    err = capsys.readouterr().err
    assert "not a bag" in err and "no bag/" in err
    assert rebuild_main([str(tmp_path / "runs")]) == 2
    assert "not a bag" in capsys.readouterr().err


def test_the_recorders_quarantine_reports_sum_up_over_a_runs_segments(tmp_path, clean):
    from sgim_nodes.bag.run_folder import quarantine_summary

    run = _run_folder(tmp_path, clean)
    samples.write_bag(run / "bag.resume1", [])
    samples.write_bag(run / "bag.resume2", [])
    (run / "bag.quarantine.yaml").write_text(yaml.safe_dump({
        "total_quarantined": 3, "quarantined": {"movements": {"duplicate": 2},
                                                "competences": {"non-finite": 1}},
        "write_error": None}))
    (run / "bag.resume1.quarantine.yaml").write_text(yaml.safe_dump({
        "total_quarantined": 1, "quarantined": {"movements": {"duplicate": 1}},
        "write_error": "could not write a movements message: OSError: [Errno 28] No space"}))
    assert quarantine_summary(run) == {
        "total": 4, "by_topic": {"movements": {"duplicate": 3},
                                 "competences": {"non-finite": 1}},
        "write_errors": {"bag.resume1": "could not write a movements message: OSError: "
                                        "[Errno 28] No space"},
        "unreported": ["bag.resume2"]}


def test_a_re_execution_the_simulator_never_logged_is_named_a_forgery(tmp_path, clean):
    """A signed re-execution is the simulator's when its log says it made it; when the run's
    logs say nothing of it, another holder of the run's key made it, and the warning says so
    rather than blame the simulator."""
    from sgim_ros.record_key import KEY_FILE, REEXECUTION_LOG

    redo = samples.movement(40, np.random.default_rng(3), attempt=1)
    messages = _after_movement(clean, 40, [("movements", redo)])

    def warned(name: str, log: str | None) -> str:
        run = _run_folder(tmp_path / name, messages)
        if log is not None:
            (run / "logs").mkdir()
            (run / "logs" / "sim_bridge.log").write_text(log)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            records = load_run(run / "bag")
        assert records.superseded == [40]  # the learner used it either way
        return " ".join(str(w.message) for w in caught if issubclass(w.category, BagReadWarning))

    made = warned("made", "[WARN] [sim_bridge]: "
                  + REEXECUTION_LOG.format(index=40, attempt=1) + ": its client got no answer")
    assert "[40] re-executed after the simulator gave no answer" in made
    assert "did not make" not in made
    forged = warned("forged", "[INFO] [sim_bridge]: fishing world ready\n")
    assert "[40] replaced by a signed re-execution that the run's simulator did not make" in forged
    assert KEY_FILE in forged and "gave no answer" not in forged
    alone = warned("alone", None)  # a bag without its run's logs: nothing to ask
    assert "[40] re-executed after the simulator gave no answer" in alone
