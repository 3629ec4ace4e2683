"""Pace control from the terminal teacher: teacher turns, step, pause, resume, the run's end."""

from __future__ import annotations

import subprocess
import threading
import time

import pytest

from sgim_nodes.core.config import LearnerConfig
from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS, PERIOD = 200, 100
IMITATIONS = LearnerConfig().imitation_count


class Prompt:
    """The run's terminal: type lines, wait for what the prompt prints."""

    def __init__(self, child: subprocess.Popen) -> None:
        self.child, self.lines = child, []
        self._reader = threading.Thread(target=lambda: self.lines.extend(child.stdout),
                                        daemon=True)
        self._reader.start()

    def text(self) -> str:
        return "".join(self.lines)

    def wait_for(self, words: str, timeout: float = 120.0, start: int = 0) -> None:
        deadline = time.monotonic() + timeout
        while words not in self.text()[start:]:
            assert self.child.poll() is None or words in self.text()[start:], self.text()[-3000:]
            assert time.monotonic() < deadline, f"{words!r} never came:\n{self.text()[-3000:]}"
            time.sleep(0.1)

    def type(self, line: str) -> int:
        start = len(self.text())
        self.child.stdin.write(line + "\n")
        self.child.stdin.flush()
        return start


def test_turns_step_pause_and_the_end_of_the_run_at_the_prompt(ros_processes, ros_domain,
                                                               tmp_path):
    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.reader import load_run

    child = ros_processes.start("pace-run", [
        RUN, "sgim-d", "--seed", "5", "--movements", str(MOVEMENTS), "--eval-every", "0",
        "--period", str(PERIOD), "--teacher", "human", "--wait-for-teacher", "forever",
        "--runs-dir", str(tmp_path), "--name", "run", "--domain", str(ros_domain),
        "--timeout", "300"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    term = Prompt(child)
    term.wait_for("your turn at movement 0 (no time limit)")
    time.sleep(2.0)
    term.wait_for("movements: 0/200", start=term.type("status"))  # the run waits for us
    start = term.type("step 3")
    term.wait_for("stepping 3 movements", start=start)
    term.wait_for("step done: paused at movement 3", start=start)
    time.sleep(1.0)
    term.wait_for("movements: 3/200", start=term.type("status"))
    start = term.type("resume")
    term.wait_for("resumed", start=start)
    start = term.type("pause")
    term.wait_for("pausing at movement", start=start)
    time.sleep(1.5)
    mark = len(term.text())
    term.type("status")
    term.wait_for("movements: ", start=mark)
    paused = int(term.text()[mark:].split("movements: ")[1].split("/")[0])
    time.sleep(1.5)
    mark = len(term.text())
    term.type("status")
    term.wait_for(f"movements: {paused}/200", start=mark)  # paused means paused
    assert paused < PERIOD
    term.type("resume")
    term.wait_for(f"your turn at movement {PERIOD}")
    start = term.type("teach 0")
    term.wait_for("sent demonstration 1 at movement 100", start=start)
    # The run ends by itself; the prompt says so and leaves without being killed.
    term.wait_for("the run is over (finished) at movement 200", timeout=200)
    assert child.wait(timeout=120) == 0, term.text()[-3000:]
    assert "Traceback" not in term.text()

    run = load_run(tmp_path / "run" / "bag")
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    (demo,) = run.demonstrations
    assert demo.source == "human" and demo.movement_index == PERIOD
    follow = run.movements[PERIOD: PERIOD + IMITATIONS]
    assert all(m.process == Movement.PROCESS_IMITATION for m in follow)
