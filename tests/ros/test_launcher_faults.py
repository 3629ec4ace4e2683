"""The launcher under faults: it never reports success on failure, leaves no node behind
whatever kills it, holds its domain and run folder while a node lives, and every wait ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from sgim_nodes.graph.processes import run_node_pids
from tests.conftest import REPO, ROS2RUN

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
SILENT = [sys.executable, str(REPO / "tests" / "ros" / "peers" / "silent_peer.py")]


def wait_for(condition, timeout: float, what: str, interval: float = 0.1):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(interval)
    pytest.fail(f"timed out after {timeout:g} s waiting for {what}")


def progress(run_dir: Path, segment: str = "") -> int:
    """The arbiter's last logged movement count (in a resumed segment's logs: `segment`)."""
    import re

    from sgim_nodes.graph.processes import node_log

    try:
        text = node_log(run_dir / "logs" / segment, "social_interaction").read_text(
            errors="replace")
    except OSError:
        return 0
    found = re.findall(r"(\d+)/\d+ movements", text)
    return int(found[-1]) if found else 0


def metadata(run_dir: Path) -> dict:
    return yaml.safe_load((run_dir / "metadata.yaml").read_text())


def launch(ros_processes, name: str, *argv: str, **popen) -> subprocess.Popen:
    popen.setdefault("stdout", subprocess.PIPE)
    popen.setdefault("stderr", subprocess.STDOUT)
    return ros_processes.start(name, [RUN, *argv], text=True, **popen)


def finish(launcher: subprocess.Popen, timeout: float) -> str:
    """A launcher's output once it ends. One that outlives `timeout` is asked for its threads'
    stacks first (SIGUSR1: into its launcher.log, which the failure report shows)."""
    try:
        return launcher.communicate(timeout=timeout)[0]
    except subprocess.TimeoutExpired:
        if launcher.poll() is None:
            launcher.send_signal(signal.SIGUSR1)
            time.sleep(2)
        raise


def test_a_killed_launcher_leaves_no_node_and_holds_its_domain_until_they_end(
        ros_processes, tmp_path):
    from sgim_nodes.graph.domain import DomainInUse, hold_run_domain, reserve_domain

    run_dir = tmp_path / "killed"
    # The evaluator's process lingers 4 s after its node ends (a slow shutdown), holding what
    # it inherited: the domain must stay reserved until it is gone.
    linger = "sh -c 'trap \"\" INT TERM HUP; \"$@\"; sleep 4' linger"
    child = launch(ros_processes, "run-killed", "random", "--movements", "300",
                   "--eval-every", "0", "--runs-dir", str(tmp_path), "--name", "killed",
                   "--quiet", "--prefix", f"evaluator={linger}")
    wait_for(lambda: progress(run_dir) > 0, 120, "the run to make movements")
    domain = metadata(run_dir)["ros_domain_id"]
    assert len(run_node_pids(run_dir)) >= 4, run_node_pids(run_dir)
    os.kill(child.pid, signal.SIGKILL)
    finish(child, 30)
    held, deadline = 0, time.monotonic() + 60
    while run_node_pids(run_dir):
        with reserve_domain(preferred=domain) as other:
            if run_node_pids(run_dir):  # a process of the run still lives: not ours to take
                assert other.domain_id != domain
                try:  # nor another run's, named by --domain
                    taken = hold_run_domain(domain)
                except DomainInUse:
                    held += 1
                else:  # the run's last process may have ended since it was seen
                    taken.release()
                    assert not run_node_pids(run_dir), "the domain was free while the run lived"
        assert time.monotonic() < deadline, f"left behind: {run_node_pids(run_dir)}"
        time.sleep(0.1)
    assert held > 0
    with reserve_domain(preferred=domain) as again:
        assert again.domain_id == domain
    meta = metadata(run_dir)
    assert meta["outcome"] == "running"  # never "finished": the launcher could not say more

    # The run resumes (the killed launcher is named), and a second resume of it meanwhile is
    # refused by the run folder's lock.
    first = launch(ros_processes, "resume-1", "--resume", str(run_dir), "--quiet")
    wait_for(lambda: progress(run_dir, "bag.resume1") > 0, 120,
             "the resumed run to make movements")
    second = launch(ros_processes, "resume-2", "--resume", str(run_dir), "--quiet")
    output = finish(second, 60)
    assert second.returncode == 2 and "in use by another launcher" in output, output
    output = finish(first, 300)
    assert first.returncode == 0, output[-3000:]
    assert "ended without recording an outcome: it was killed" in output
    assert metadata(run_dir)["outcome"] == "finished"


def test_a_second_run_asking_for_a_run_s_domain_is_refused(ros_processes, tmp_path):
    """Two runs on one domain would mix their records: the second is refused in one line
    before it makes anything, and the first runs on alone to its budget."""
    first_dir = tmp_path / "first"
    first = launch(ros_processes, "run-first", "random", "--movements", "150",
                   "--eval-every", "0", "--runs-dir", str(tmp_path), "--name", "first",
                   "--quiet")
    wait_for(lambda: progress(first_dir) > 0, 120, "the first run to make movements")
    domain = metadata(first_dir)["ros_domain_id"]
    second = subprocess.run(
        [RUN, "random", "--movements", "150", "--eval-every", "0", "--runs-dir",
         str(tmp_path), "--name", "second", "--quiet", "--domain", str(domain)],
        capture_output=True, text=True, timeout=120)
    said = (second.stdout + second.stderr).strip().splitlines()
    assert second.returncode == 2, said
    assert len(said) == 1 and f"ROS domain {domain} is held by another run" in said[0], said
    assert not (tmp_path / "second").exists()
    output = finish(first, 300)
    assert first.returncode == 0, output[-3000:]
    meta = metadata(first_dir)
    assert meta["outcome"] == "finished" and meta["movements_done"] == 150
    assert meta["quarantine"]["total"] == 0, meta["quarantine"]


def test_ctrl_c_with_output_piped_stops_every_node(ros_processes, tmp_path):
    """`run_experiment.sh ... | tee log`, then Ctrl-C: tee dies with the launcher's pipe."""
    run_dir = tmp_path / "piped"
    child = launch(ros_processes, "run-piped", "random", "--movements", "5000",
                   "--eval-every", "0", "--runs-dir", str(tmp_path), "--name", "piped")
    wait_for(lambda: progress(run_dir) > 0, 120, "the run to make movements")
    child.stdout.close()  # the reader (tee) is gone: every write now meets a broken pipe
    child.send_signal(signal.SIGINT)
    code = child.wait(timeout=120)
    meta = metadata(run_dir)
    log = (run_dir / "logs" / "launcher.log").read_text()
    # Seen once under load: exit 1 although metadata.yaml said 130; the terminal output is
    # gone (the pipe is closed), so a failure says what the run folder holds.
    assert code == 130, (f"exit code {code}; metadata: {meta.get('outcome')!r}, exit_code "
                         f"{meta.get('exit_code')}; launcher.log ends: {log[-600:]!r}")
    assert not run_node_pids(run_dir)
    assert meta["outcome"].startswith("interrupted by SIGINT")
    assert "interrupted by SIGINT" in log  # what the terminal missed is in the run's log


def test_a_recorder_that_cannot_write_fails_the_run_and_resume_repairs_it(ros_processes,
                                                                          tmp_path):
    """A full disk, as the recorder meets it: writes fail (here past a file-size limit)."""
    run_dir = tmp_path / "full"
    child = launch(ros_processes, "run-full", "random", "--movements", "200",
                   "--eval-every", "100", "--runs-dir", str(tmp_path), "--name", "full",
                   "--quiet", "--prefix", "recorder=prlimit --fsize=4000")
    output = finish(child, 300)
    assert child.returncode == 1, output[-3000:]
    meta = metadata(run_dir)
    assert meta["outcome"].startswith("failed: the recorder"), meta["outcome"]
    assert "Errno 27" in meta["outcome"] or "File too large" in meta["outcome"]
    assert "recorder" in output and "failed" in output
    assert meta["quarantine"]["write_errors"], meta["quarantine"]  # the recorder's report

    from sgim_nodes.graph.run_folder import recorded_count

    recorded = recorded_count(run_dir)
    assert recorded < 200
    again = launch(ros_processes, "resume-full", "--resume", str(run_dir), "--quiet")
    output = finish(again, 300)
    assert again.returncode == 0, output[-3000:]
    if meta["movements_done"] > recorded:  # the launcher saw more than the bag kept
        assert f"end at movement {recorded}" in output and "were lost" in output
    from sgim_nodes.bag.resume import load_run_folder

    run = load_run_folder(run_dir)
    assert [m.index for m in run.movements] == list(range(1, 201))
    assert metadata(run_dir)["outcome"] == "finished"


def test_a_simulator_that_never_answers_ends_the_run_with_a_message(ros_processes, tmp_path):
    run_dir = tmp_path / "silent"
    child = launch(ros_processes, "run-silent", "saggriac", "--movements", "50",
                   "--runs-dir", str(tmp_path), "--name", "silent", "--quiet",
                   "--param", "service_timeout=1.0", "--param", "service_retries=2",
                   "--prefix", f"sim_bridge={' '.join(SILENT)} sim_bridge execute_action")
    output = finish(child, 180)
    assert child.returncode == 1, output[-3000:]
    outcome = metadata(run_dir)["outcome"]
    assert outcome.startswith("aborted") and "reach_goal" in outcome, outcome
    from sgim_nodes.graph.processes import node_log

    explorer = node_log(run_dir / "logs", "low_level_explorer").read_text()
    assert "no answer from execute_action for movement 1 after 3 tries" in explorer


def test_the_arbiter_gives_up_on_a_recorder_that_never_answers(ros_processes, tmp_path):
    ros_processes.start("silent-recorder", [*SILENT, "recorder", "recorder_ready"])
    ros_processes.start("silent-sim", [*SILENT, "sim_bridge", "execute_action"])
    arbiter = ros_processes.start(
        "arbiter", [ROS2RUN, "sgim_nodes", "social_interaction", "--ros-args", "-p",
                    "learner:=random", "-p", "wait_for_evaluation:=false", "-p",
                    "startup_timeout:=8.0", "-p", "settle_time:=0.0"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = arbiter.communicate(timeout=120)
    assert arbiter.returncode == 1, output
    assert "waiting for recorder_ready, the recorder did not answer" in output


def test_a_run_longer_than_its_timeout_fails_and_says_so(ros_processes, tmp_path):
    run_dir = tmp_path / "slow"
    child = launch(ros_processes, "run-slow", "random", "--movements", "100000",
                   "--runs-dir", str(tmp_path), "--name", "slow", "--quiet", "--timeout", "20")
    output = finish(child, 180)
    assert child.returncode == 1
    assert "timed out after 20 s (--timeout)" in metadata(run_dir)["outcome"], output[-2000:]
    assert not run_node_pids(run_dir)


def test_resuming_a_folder_whose_metadata_has_no_learner_says_what_to_fix(ros_processes,
                                                                         tmp_path):
    run_dir = tmp_path / "broken"
    run_dir.mkdir()
    (run_dir / "metadata.yaml").write_text("seed: 2\nmovements: 300\noutcome: failed\n")
    (run_dir / "params.yaml").write_text(
        "/**:\n  ros__parameters:\n    learner: sgim-d\n    seed: 2\n")
    child = launch(ros_processes, "resume-broken", "--resume", str(run_dir))
    output = finish(child, 120)
    assert child.returncode == 2
    assert "metadata.yaml has no 'learner'" in output and "params.yaml says learner: sgim-d" \
        in output
    assert "Traceback" not in output
