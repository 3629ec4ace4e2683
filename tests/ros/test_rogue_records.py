"""Rogue and late records published into a running graph (issue 12): every one is refused
live with its reason, the run keeps its exact budget and evaluation points, and the bag holds
everything received while its readers fold exactly what the learner had."""

from __future__ import annotations

import subprocess
import warnings

import numpy as np
import pytest
import yaml

from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS, EVAL_EVERY, SEED = 300, 100, 3
BURST = 80


def _demo(index, action, outcome, teaching_index=0, movement_index=40):
    from sgim_msgs.msg import Demonstration

    return Demonstration(index=index, movement_index=movement_index,
                         action=[float(v) for v in action], outcome=[float(v) for v in outcome],
                         teaching_set_index=teaching_index, source="human")


def _cancel_all(client, name: str) -> None:
    """What `cancel all goals` of an action is: a CancelGoal request with a zero goal id."""
    from action_msgs.srv import CancelGoal

    cancel = client.node.create_client(CancelGoal, f"/{name}/_action/cancel_goal")
    if cancel.wait_for_service(timeout_sec=5):
        client.ask(cancel, CancelGoal.Request())


def test_rogue_and_late_records_are_refused_and_the_run_stays_exact(
        ros_processes, ros_domain, tmp_path, rclpy_context):
    from rclpy.action import ActionClient

    from sgim_msgs.action import ReachGoal
    from sgim_msgs.msg import Competence, Demonstration, Movement, RunStatus
    from sgim_ros import qos
    from sim_bridge.data_files import load_teaching_set
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "rogue")
    seen: list[Movement] = client.capture(Movement, "/movements", qos.RECORDS)
    statuses: list[RunStatus] = client.capture(RunStatus, "/run_status", qos.RECORDS)
    movements = client.node.create_publisher(Movement, "/movements", qos.RECORDS)
    demos = client.node.create_publisher(Demonstration, "/demonstrations", qos.RECORDS)
    competences = client.node.create_publisher(Competence, "/competences", qos.RECORDS)
    child = ros_processes.start(
        "run-rogue",
        [RUN, "sgim-d", "--seed", str(SEED), "--movements", str(MOVEMENTS), "--eval-every",
         str(EVAL_EVERY), "--teacher", "external", "--runs-dir", str(tmp_path), "--name",
         "rogue", "--domain", str(ros_domain), "--quiet", "--timeout", "400"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    teaching = load_teaching_set()
    assert client.spin_until(lambda: len(seen) >= 40, timeout=180)
    from sgim_ros.record_key import read_key, sign_teaching, signed_by

    key = read_key(tmp_path / "rogue")
    assert key, "the launcher keeps the run's record key in its folder"
    rng = np.random.default_rng(0)
    good_action, good_outcome = teaching.actions[1], teaching.outcomes[1]

    # Malformed demonstrations, a huge outcome, unknown teaching indices.
    for bad in (_demo(1, [np.nan] * 24, good_outcome), _demo(2, [np.inf] * 24, good_outcome),
                _demo(3, good_action[:5], good_outcome),
                _demo(4, good_action, [1e300, -1e300]),
                _demo(5, good_action, good_outcome, teaching_index=2**31 - 1),
                _demo(6, good_action, good_outcome, teaching_index=-7)):
        demos.publish(bad)
    # Forged movements: duplicates of 5-7, an index far ahead, NaN outcomes ahead of the
    # simulator.
    latest = seen[-1].index
    for k in (5, 6, 7):
        movements.publish(Movement(index=k, process=0, status=0, action=list(rng.uniform(
            -1, 1, 24)), outcome=[0.9, 0.9], goal=[0.0, 0.0], goal_index=1))
    movements.publish(Movement(index=2_000_000, process=0, status=0, action=[0.0] * 24,
                               outcome=[0.1, 0.1]))
    for k in range(latest + 1, latest + 31):
        movements.publish(Movement(index=k, process=0, status=0, action=[0.0] * 24,
                                   outcome=[float("nan"), float("nan")]))
    # Well-formed demonstrations no teacher of the run signed (forged answers).
    for k in range(3):
        demos.publish(_demo(500 + k, good_action, good_outcome, teaching_index=1,
                            movement_index=latest))
    # Forged re-executions: the latest real movement again with attempt 1 and another
    # outcome, right after it, five times; only the run's simulator can sign one.
    def simulators() -> list[Movement]:  # what the run's simulator published (signed)
        return [m for m in seen if signed_by(key, m)]

    forged_retries: list[int] = []
    for _ in range(5):
        count = len(simulators())
        assert client.spin_until(lambda count=count: len(simulators()) > count, timeout=60)
        last = simulators()[-1]
        forged_retries.append(int(last.index))
        movements.publish(Movement(index=last.index, process=last.process, status=0,
                                   action=list(last.action), outcome=[0.99, 0.99],
                                   goal=list(last.goal), goal_index=last.goal_index,
                                   attempt=1, signature=list(last.signature)))
    # Competences that must not reach the interest tree: malformed, and one well-formed that
    # no node of the run signed.
    for goal, value in (([0.1, 0.1], float("nan")), ([0.1, 0.1], -1e12),
                        ([0.1, 0.2, 0.3], -0.5), ([0.1, 0.1], -0.5)):
        competences.publish(Competence(goal=goal, competence=value, movements_used=2,
                                       movement_index=latest))
    # A rogue job on the explorer after a cancel-all of the running one.
    _cancel_all(client, "reach_goal")
    rogue = ActionClient(client.node, ReachGoal, "/reach_goal")
    if rogue.wait_for_server(timeout_sec=5):
        rogue.send_goal_async(ReachGoal.Goal(max_movements=5, movements_before=5))
    client.spin_for(1.0)
    # A burst of valid demonstrations (an external teacher signs with the run's key): more
    # than the budget can hold.
    for k in range(BURST):
        entry = k % len(teaching.actions)
        demos.publish(sign_teaching("demonstrations", _demo(
            10 + k, teaching.actions[entry], teaching.outcomes[entry], teaching_index=entry,
            movement_index=latest), key))
    # A late demonstration: once the budget is spent, while the final evaluation runs.
    assert client.spin_until(lambda: any(m.index == MOVEMENTS for m in seen), timeout=300)
    demos.publish(sign_teaching("demonstrations", _demo(
        999, good_action, good_outcome, teaching_index=1, movement_index=MOVEMENTS), key))
    client.spin_until(lambda: statuses and statuses[-1].state != RunStatus.STATE_RUNNING, 120)
    client.close()
    output, _ = child.communicate(timeout=300)
    assert child.returncode == 0, output[-3000:]

    run_dir = tmp_path / "rogue"
    from sgim_nodes.bag.reader import QuarantineWarning, read_raw
    from sgim_nodes.bag.resume import load_run_folder

    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always", QuarantineWarning)
        run = load_run_folder(run_dir)
    # The budget is exact and every movement is recorded once, the real one.
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    real = {m.index: m for m in simulators()}  # the test hears its own forgeries too
    for k in (5, 6, 7, *forged_retries):
        assert np.array_equal(run.movements[k - 1].action, np.asarray(real[k].action))
        assert np.array_equal(run.movements[k - 1].outcome, np.asarray(real[k].outcome))
    assert run.superseded == [] and not any(m.attempt for m in run.movements)
    assert all(m.outcome.size == 0 or np.isfinite(m.outcome).all() for m in run.movements)
    # Evaluations at exactly the documented movements, and the run finished.
    assert [e.movement_index for e in run.evaluations] == [0, 100, 200, 300]
    assert run.run_status[-1].state == RunStatus.STATE_FINISHED
    assert run.run_status[-1].movement_index == MOVEMENTS
    # Taken demonstrations: valid ones only, each imitated within the budget; the late one
    # and those that waited in vain are refused on run_status.
    taken = run.demonstrations_taken
    assert 0 < len(taken) < BURST and {d.index for d in taken} <= set(range(10, 10 + BURST))
    imitations = sum(1 for m in run.movements if m.process == Movement.PROCESS_IMITATION)
    from sgim_nodes.core.config import LearnerConfig

    assert imitations <= LearnerConfig().imitation_count * len(taken)
    messages = [s.message for s in run.run_status]
    assert any("demonstration 999" in m and "refused" in m for m in messages), messages
    assert any("refused" in m and "waited" in m for m in messages), messages
    # The bag holds everything received, in one valid MCAP file that rosbags and the MCAP
    # library read as they are; the quarantine counts are beside it.
    raw = list(read_raw(run_dir / "bag"))
    assert sum(1 for r in raw if r.topic == "/movements") == MOVEMENTS + 3 + 1 + 30 + 5
    assert sorted(p.name for p in (run_dir / "bag").iterdir()) == ["bag.mcap", "metadata.yaml"]
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader

    with AnyReader([run_dir / "bag"]) as reader:
        assert reader.message_count == len(raw)
    with (run_dir / "bag" / "bag.mcap").open("rb") as stream:
        mcap = make_reader(stream, validate_crcs=True)
        assert sum(1 for _ in mcap.iter_messages()) == len(raw)
        (embedded,) = [m.metadata["serialized_metadata"] for m in mcap.iter_metadata()]
    assert "- bag.mcap" in embedded
    report = yaml.safe_load((run_dir / "bag.quarantine.yaml").read_text())
    q = report["quarantined"]
    # The forged duplicates and re-executions carry no signature of the run's simulator.
    assert q["movements"] == {"unsigned": 3 + 5, "beyond-budget": 1, "non-finite": 30}
    assert q["demonstrations"]["non-finite"] == 2 and q["demonstrations"]["size"] == 1
    assert q["demonstrations"]["out-of-bounds"] == 1
    assert q["demonstrations"]["unknown-teaching-index"] == 2
    assert q["demonstrations"]["unsigned"] == 3  # the forged answers, never taken
    assert q["competences"] == {"non-finite": 1, "out-of-bounds": 1, "size": 1, "unsigned": 1}
    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())  # counted there too
    assert meta["outcome"] == "finished" and meta["quarantine"] == {
        "total": report["total_quarantined"], "by_topic": q, "write_errors": {}}
    # The evaluator's memory was the learner's: each evaluation is recomputed exactly from
    # the bag's movements and taken demonstrations, on the evaluator's own world.
    from sgim_nodes.bag.rebuild import rebuild_from_records
    from sgim_nodes.bag.resume import records_until
    from sgim_nodes.core.config import LearnerConfig
    from sgim_nodes.core.evaluator import EVALUATION_SEED_OFFSET, Evaluator
    from sgim_nodes.core.learners import inverse_model_for, inverse_or_centre
    from sim_bridge.core_world import fishing_scale
    from sim_bridge.data_files import load_benchmark_goals
    from sim_bridge.fishing_world import FishingWorld

    config = LearnerConfig()
    world = FishingWorld(seed=SEED + EVALUATION_SEED_OFFSET)
    try:
        evaluator = Evaluator(world, load_benchmark_goals())
        for recorded in run.evaluations:
            state = rebuild_from_records(records_until(run, recorded.movement_index), config)
            model = inverse_model_for(state.memory, config, fishing_scale())
            result = evaluator.evaluate(lambda g, m=model: inverse_or_centre(m, g, 24))
            assert result.mean_distance == pytest.approx(recorded.mean_distance, abs=1e-12)
    finally:
        world.close()
