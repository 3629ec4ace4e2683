"""The launcher's own plumbing: messages that survive a closed pipe, reasons quoted from logs."""

from __future__ import annotations

import os

import pytest

from sgim_nodes.graph.supervise import SafeStream, log_reason


def test_messages_survive_a_closed_output_pipe_and_still_reach_the_run_log(tmp_path):
    read_end, write_end = os.pipe()
    stream = SafeStream(os.fdopen(write_end, "w"))
    stream.log = open(tmp_path / "launcher.log", "w")  # noqa: SIM115
    stream.write("before\n")
    assert os.read(read_end, 100) == b"before\n"
    os.close(read_end)  # `| tee log`, and tee is gone
    stream.write("interrupted by SIGINT\n")  # no BrokenPipeError
    stream.write("after\n")
    stream.flush()
    assert stream.broken
    stream.log.close()
    assert (tmp_path / "launcher.log").read_text() == "before\ninterrupted by SIGINT\nafter\n"


def test_the_reason_quoted_is_the_first_logged_error(tmp_path):
    log = tmp_path / "recorder.log"
    log.write_text(
        "\x1b[37;1m2026 [RTPS_TRANSPORT_SHM Error] Failed to create segment\n"
        "[INFO] [1796.1] [recorder]: recording 7 topics\n"
        "[ERROR] [1796.2] [recorder]: could not write the bag: [Errno 28] No space left\n"
        "[ERROR] [1796.3] [recorder]: could not write a movements message: part exists\n")
    assert log_reason(log) == "could not write the bag: [Errno 28] No space left"


def test_without_a_logged_error_the_reason_is_the_exception_of_a_traceback(tmp_path):
    log = tmp_path / "evaluator.log"
    log.write_text("Traceback (most recent call last):\n  File \"x.py\", line 1\n"
                   "ValueError: data must be finite\n")
    assert log_reason(log) == "ValueError: data must be finite"
    assert log_reason(tmp_path / "missing.log") == ""


@pytest.mark.ros  # the run's parameters are checked against the nodes' declarations
def test_a_resumed_runs_failure_names_the_log_of_its_own_segment(tmp_path):
    """A resumed run's nodes log to logs/bag.resume1/: a node that stops is quoted from there,
    not from the first segment's log of the same name."""
    from types import SimpleNamespace

    import yaml

    from sgim_nodes.graph.experiment import plan_new, plan_resume
    from sgim_nodes.graph.experiment_options import parse_args
    from sgim_nodes.graph.run_folder import write_metadata
    from sgim_nodes.graph.supervise import Supervisor
    from tests.bag.samples import synthetic_run, write_bag

    plan = plan_new(parse_args(["random", "--movements", "60", "--runs-dir", str(tmp_path),
                                "--name", "run"]))
    plan.lock.release()
    plan.params_file.write_text(yaml.safe_dump(plan.values.to_yaml()))
    write_metadata(plan.run_dir, dict(plan.meta, outcome="failed: x", movements_done=40))
    messages = synthetic_run(n=60)  # cut after movement 40
    cut = next(i for i, (t, m) in enumerate(messages) if t == "movements" and m.index == 40)
    write_bag(plan.run_dir / "bag", messages[:cut + 1])
    plan.log_dir.mkdir()
    (plan.log_dir / "evaluator.log").write_text("[ERROR] [1.0] [evaluator]: the first run's\n")

    resumed = plan_resume(parse_args(["--resume", str(plan.run_dir)]))
    resumed.lock.release()
    assert resumed.log_dir == plan.run_dir / "logs" / "bag.resume1"
    assert resumed.params_file == plan.run_dir / "params.bag.resume1.yaml"
    resumed.log_dir.mkdir()
    (resumed.log_dir / "evaluator.log").write_text(
        "[ERROR] [2.0] [evaluator]: no answer from execute_action\n")
    supervisor = Supervisor(resumed.nodes, launch=None, log_dir=resumed.log_dir, timeout=1.0,
                            progress=SimpleNamespace(count=45))
    message = supervisor.failure("evaluator", 1)
    assert message == ("node evaluator stopped (exit 1) at movement 45: no answer from "
                       f"execute_action; see {resumed.log_dir / 'evaluator.log'}")
