"""What a user meets in the first hour, as the guide tells it: `./run.sh` with options of the
launcher, Ctrl-C on a run that draws its progress bar, `replay` to a listener of some topics."""

from __future__ import annotations

import re
import signal
import subprocess
import time

import pytest
import yaml

from tests.bag import ros_helpers as h
from tests.bag import samples
from tests.conftest import REPO
from tests.ros.graph_client import GraphClient
from tests.ros.test_launcher_faults import progress, wait_for

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")


def test_run_sh_honours_runs_dir_and_name(ros_processes, ros_domain, tmp_path):
    """Both are the launcher's options, and analyze must read the folder they make; a relative
    --runs-dir is the caller's, as for any command."""
    child = ros_processes.start(
        "run-sh", [str(REPO / "run.sh"), "--movements", "20", "--eval-every", "0", "--quiet",
                   "--no-markers", "--runs-dir", "mine", "--name=first", "--domain",
                   str(ros_domain)],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output = child.communicate(timeout=240)[0]
    assert child.returncode == 0, output[-3000:]
    run_dir = tmp_path / "mine" / "first"
    assert (run_dir / "figures" / "results.md").is_file(), output[-3000:]
    assert yaml.safe_load((run_dir / "metadata.yaml").read_text())["outcome"] == "finished"
    assert "mine/first/figures/" in output
    assert not (REPO / "runs" / "main" / "first").exists()


def test_ctrl_c_says_how_the_run_ended_after_the_progress_bar(ros_processes, ros_domain,
                                                              tmp_path):
    """With the bar drawn, the outcome and the --resume hint are lines of their own after it:
    written on the bar's line, the bar's next drawing went over them."""
    run_dir = tmp_path / "bar"
    child = ros_processes.start(
        "run-bar", [RUN, "random", "--movements", "5000", "--eval-every", "0", "--no-markers",
                    "--runs-dir", str(tmp_path), "--name", "bar", "--domain", str(ros_domain)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wait_for(lambda: progress(run_dir) > 0, 120, "the run to make movements")
    child.send_signal(signal.SIGINT)
    output = child.communicate(timeout=120)[0]
    assert child.returncode == 130, output[-3000:]
    assert "mv/s" in output  # the bar was drawn
    outcome = [i for i, line in enumerate(re.split(r"[\r\n]", output))
               if line.startswith("run_experiment: interrupted by SIGINT at movement ")]
    assert outcome, f"no outcome line of its own: {output[-1500:]!r}"
    tail = output[output.rindex("run_experiment: interrupted by SIGINT"):]
    assert "--resume carries on" in tail.splitlines()[0], repr(tail)
    assert "mv/s" not in tail, f"the bar is drawn after the outcome: {tail!r}"
    assert "pybullet build time" not in output


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context, "first_hour_client")
    yield c
    c.close()


def test_replay_plays_to_a_listener_of_some_topics(ros_processes, client, tmp_path):
    """rviz2 or a node of one's own hears only some topics: replay says at once that it
    waits, then plays to them, naming the topics nobody hears, instead of refusing."""
    from sgim_msgs.msg import Movement
    from sgim_ros import qos

    bag = samples.write_bag(tmp_path / "run", samples.synthetic_run(40, seed=2))
    received = client.capture(Movement, "/movements", qos.RECORDS)
    started = time.monotonic()
    child = ros_processes.start(
        "replay_some", [*h.node_command("replay", "sgim_nodes.bag.replay"), str(bag),
                        "--rate", "50", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert client.spin_until(lambda: child.poll() is not None, 25), "replay did not play"
    output = child.communicate(timeout=10)[0]
    assert child.returncode == 0, output
    assert time.monotonic() - started < 25  # not the whole --wait-subscribers
    assert "waiting up to 30 s for subscribers" in output, output
    assert "nobody hears" in output and "/region_map (0/1)" in output, output
    assert "/movements (" not in output, output
    assert client.spin_until(lambda: len(received) == 40, 10), len(received)
    assert [m.index for m in received] == list(range(1, 41))
