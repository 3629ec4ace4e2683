"""The launcher's own plumbing: messages that survive a closed pipe, reasons quoted from logs,
a teardown that always ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from sgim_nodes.graph.supervise import SafeStream
from sgim_nodes.graph.supervisor import log_reason


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

    from sgim_nodes.graph.experiment_options import parse_args
    from sgim_nodes.graph.plan import plan_new, plan_resume
    from sgim_nodes.graph.process_plan import process_plan
    from sgim_nodes.graph.run_folder import write_metadata
    from sgim_nodes.graph.supervisor import Supervisor
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
    supervisor = Supervisor(process_plan(resumed.nodes, separate=True), launch=None,
                            log_dir=resumed.log_dir, timeout=1.0,
                            progress=SimpleNamespace(count=45))
    message = supervisor.failure("evaluator", 1)
    assert message == ("node evaluator stopped (exit 1) at movement 45: no answer from "
                       f"execute_action; see {resumed.log_dir / 'evaluator.log'}")


@pytest.fixture
def python_child(tmp_path):
    """Start child Pythons (`_python`); any left running at the end is killed."""
    children: list[subprocess.Popen] = []

    def start(body: str, **popen) -> subprocess.Popen:
        children.append(_python(tmp_path, body, **popen))
        return children[-1]

    yield start
    for child in children:
        if child.poll() is None:
            child.kill()
            child.wait()


def _python(tmp_path, body: str, **popen) -> subprocess.Popen:
    """A child Python whose launcher.log is tmp_path/launcher.log, running `body`."""
    script = tmp_path / "child.py"
    script.write_text(textwrap.dedent(f"""\
        import re, sys, time
        from sgim_nodes.graph import supervise
        supervise.OUT.log = open({str(tmp_path / "launcher.log")!r}, "a")
        """) + textwrap.dedent(body))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.Popen([sys.executable, str(script)], env=env, text=True, **popen)


def test_a_teardown_stuck_in_c_code_holding_the_gil_still_ends_and_leaves_its_stack(
        python_child, tmp_path):
    # Nested quantifiers: the regex engine backtracks for hours without releasing the GIL,
    # like an rclpy call stuck in DDS; no Python timer could interrupt it.
    child = python_child("""\
        def stuck_in_c():
            re.match(r"(a+)+$", "a" * 40 + "b")
        with supervise.hard_deadline(1.0):
            stuck_in_c()
        """)
    assert child.wait(timeout=120) == 1
    log = (tmp_path / "launcher.log").read_text()
    assert "Timeout (0:00:01)!" in log and "stuck_in_c" in log


def test_a_deadline_past_a_recorded_run_ends_with_the_runs_own_exit_code(python_child,
                                                                        tmp_path):
    """The launcher's goodbye to DDS (its own node's teardown) can hang after the run is
    recorded: the stacks still go to launcher.log, and the exit code stays the run's."""
    child = python_child("""\
        def stuck_in_c():
            re.match(r"(a+)+$", "a" * 40 + "b")
        with supervise.hard_deadline(1.0, exit_code=0):
            stuck_in_c()
        """)
    assert child.wait(timeout=120) == 0
    log = (tmp_path / "launcher.log").read_text()
    assert "Timeout (0:00:01)!" in log and "stuck_in_c" in log
    child = python_child("""\
        with supervise.hard_deadline(1.0, exit_code=130):
            re.match(r"(a+)+$", "a" * 40 + "b")
        """)
    assert child.wait(timeout=120) == 130


def test_without_posix_timers_a_deadline_still_ends_the_process(python_child, tmp_path):
    """Where the C library has no timer_create, faulthandler ends the process (with 1)."""
    child = python_child("""\
        def no_timers(seconds, code):
            raise AttributeError("timer_create")
        supervise._exit_later = no_timers
        with supervise.hard_deadline(1.0, exit_code=0):
            re.match(r"(a+)+$", "a" * 40 + "b")
        """)
    assert child.wait(timeout=120) == 1
    assert "Timeout (0:00:01)!" in (tmp_path / "launcher.log").read_text()


def test_a_block_that_ends_in_time_disarms_its_deadline(python_child, tmp_path):
    child = python_child("""\
        with supervise.hard_deadline(0.5):
            pass
        time.sleep(2.0)  # past the deadline, outside the block
        """)
    assert child.wait(timeout=120) == 0
    assert "Timeout" not in (tmp_path / "launcher.log").read_text()


def test_sigusr1_writes_every_threads_stack_and_the_launcher_goes_on(python_child, tmp_path):
    child = python_child("""\
        supervise.stacks_on_request()
        def waiting_for_the_test():
            print("ready", flush=True)
            sys.stdin.readline()
        waiting_for_the_test()
        """, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    assert child.stdout.readline() == "ready\n"
    child.send_signal(signal.SIGUSR1)
    log = tmp_path / "launcher.log"
    deadline = time.monotonic() + 60
    while "waiting_for_the_test" not in log.read_text() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "waiting_for_the_test" in log.read_text()
    child.stdin.write("\n")
    child.stdin.close()
    assert child.wait(timeout=60) == 0
