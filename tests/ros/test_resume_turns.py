"""Resume loses nothing (issue 31): a teacher's demonstration recorded but not taken when the
run stopped is given again, and the resume report says, turn by turn, what was redone."""

from __future__ import annotations

import os
import signal
import subprocess
import time
import warnings

import pytest

from tests.conftest import REPO
from tests.ros.test_faults import find_process

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
PERIOD, MOVEMENTS = 50, 120


def start_run(ros_processes, ros_domain, tmp_path, *extra: str):
    """SGIM-D with a teacher every PERIOD, in tmp_path/cut; a strict teacher (a small
    tolerance) shows something at each turn."""
    return ros_processes.start(
        "run-cut", [RUN, "sgim-d", "--seed", "1", "--movements", str(MOVEMENTS),
                    "--demonstration-period", str(PERIOD), "--eval-every", "60", "--runs-dir",
                    str(tmp_path), "--name", "cut", "--domain", str(ros_domain), "--quiet",
                    "--param", "tolerance_noise=0.1", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def resume(ros_processes, ros_domain, run_dir) -> str:
    """--resume the run to its end; its output (it must finish)."""
    resumed = ros_processes.start("resume-cut", [RUN, "--resume", str(run_dir), "--quiet",
                                                 "--domain", str(ros_domain)],
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = resumed.communicate(timeout=400)
    assert resumed.returncode == 0, output[-3000:]
    return output


def test_a_demonstration_given_but_not_taken_is_given_again_on_resume(
        ros_processes, ros_domain, tmp_path, rclpy_context):
    from sgim_msgs.msg import Demonstration, Movement
    from sgim_nodes.bag.resume import load_run_folder
    from sgim_ros import qos
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "turn_cutter")
    moves = client.capture(Movement, "/movements", qos.RECORDS)
    words = client.capture(Demonstration, "/demonstrations", qos.RECORDS)
    run_dir = tmp_path / "cut"
    # A process per node: the explorer is stopped alone, while the recorder goes on.
    child = start_run(ros_processes, ros_domain, tmp_path, "--separate")
    params = str(run_dir / "params.yaml")
    # Stop the explorer at the turn's boundary: its job never ends, so the arbiter never
    # reaches the turn, while the teacher, which follows the movements, gives its word.
    assert client.spin_until(lambda: any(m.index == PERIOD for m in moves), timeout=180)
    explorer = find_process("lib/sgim_nodes/low_level_explorer", params)
    assert explorer is not None
    os.kill(explorer, signal.SIGSTOP)
    assert client.spin_until(lambda: any(w.movement_index == PERIOD for w in words), 60)
    time.sleep(2.0)  # the recorder writes the word down (it flushes every 0.5 s)
    os.kill(child.pid, signal.SIGKILL)  # the launcher dies; its nodes follow it
    os.kill(explorer, signal.SIGKILL)
    child.communicate(timeout=60)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = load_run_folder(run_dir)
    given = [w for w in before.demonstrations if w.movement_index == PERIOD and w.shown]
    assert given and not [d for d in before.demonstrations_taken
                          if d.movement_index == PERIOD], "the turn was taken: no test"
    client.close()

    output = resume(ros_processes, ros_domain, run_dir)
    assert (f"resume: the teacher's turn at movement {PERIOD}: demonstration "
            f"{given[0].index}") in output and "the turn is taken again" in output, output
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        after = load_run_folder(run_dir)
    turns = range(0, MOVEMENTS, PERIOD)
    taken = [d.movement_index for d in after.demonstrations_taken]
    assert taken == list(turns), taken  # one demonstration taken at every turn, none lost
    assert [m.index for m in after.movements] == list(range(1, MOVEMENTS + 1))
    import yaml

    meta = yaml.safe_load((run_dir / "metadata.yaml").read_text())
    redone = meta["resumed"][0]["redone"]
    assert any(f"turn at movement {PERIOD}" in line for line in redone), redone


def test_an_imitation_cut_by_a_kill_is_finished_on_resume(ros_processes, ros_domain, tmp_path,
                                                          rclpy_context):
    """A kill during a turn's imitation: the resumed run makes the imitations it owed and
    records the demonstration's competence before it goes on, and says so."""
    import yaml

    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.resume import load_run_folder
    from sgim_ros import qos
    from tests.ros.graph_client import GraphClient

    client = GraphClient(rclpy_context, "imitation_cutter")
    moves = client.capture(Movement, "/movements", qos.RECORDS)
    run_dir = tmp_path / "cut"
    # A process per node: the imitation node is stopped alone, while the recorder goes on.
    child = start_run(ros_processes, ros_domain, tmp_path, "--separate")
    params = str(run_dir / "params.yaml")
    # Stop the imitation node at the turn's first imitation, then kill the run.
    assert client.spin_until(lambda: any(m.index == PERIOD + 1 for m in moves), timeout=180)
    imitation = find_process("lib/sgim_nodes/imitation", params)
    assert imitation is not None
    os.kill(imitation, signal.SIGSTOP)
    time.sleep(2.0)  # the recorder writes the imitations made down
    os.kill(child.pid, signal.SIGKILL)
    os.kill(imitation, signal.SIGKILL)
    child.communicate(timeout=60)
    client.close()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = load_run_folder(run_dir)
    made = [m.index for m in before.movements if m.process == Movement.PROCESS_IMITATION
            and m.index > PERIOD]
    assert 1 <= len(made) < 5, f"the imitation was not cut ({made}): no test"

    output = resume(ros_processes, ros_domain, run_dir)
    assert "resume: the imitation of demonstration" in output, output[-3000:]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        after = load_run_folder(run_dir)
    imitated = [m.index for m in after.movements if m.process == Movement.PROCESS_IMITATION
                and PERIOD < m.index <= 2 * PERIOD]
    assert imitated == list(range(PERIOD + 1, PERIOD + 6)), imitated  # all five, once
    measured = [c for c in after.competences if c.from_demonstration
                and PERIOD < c.movement_index <= 2 * PERIOD]
    assert [(c.movement_index, c.movements_used) for c in measured] == [(PERIOD + 5, 5)]
    assert [m.index for m in after.movements] == list(range(1, MOVEMENTS + 1))
    redone = yaml.safe_load((run_dir / "metadata.yaml").read_text())["resumed"][0]["redone"]
    assert any("imitation of demonstration" in line for line in redone), redone
