"""Pace control from the terminal teacher: teacher turns, step, pause, resume, the run's end."""

from __future__ import annotations

import re
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
        "--demonstration-period", str(PERIOD), "--teacher", "human", "--wait-for-teacher",
        "forever", "--runs-dir", str(tmp_path), "--name", "run", "--domain", str(ros_domain),
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
    # The prompt has the terminal to itself: no progress bar (run without --quiet), progress
    # is a line above the prompt instead.
    assert "mv/s" not in term.text()
    assert re.search(r"\nprogress: movement 1\d\d/200 \(50 %\)\n", term.text())

    run = load_run(tmp_path / "run" / "bag")
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    (demo,) = run.demonstrations
    assert demo.source == "human" and demo.movement_index == PERIOD
    follow = run.movements[PERIOD: PERIOD + IMITATIONS]
    assert all(m.process == Movement.PROCESS_IMITATION for m in follow)


@pytest.mark.parametrize(("teacher", "wait"), [("web", "1.5"), ("human", "0")])
def test_wait_for_teacher_seconds_ends_each_turn_and_zero_never_waits(
        ros_processes, ros_domain, tmp_path, teacher, wait):
    """Nobody teaches: with SECONDS the run waits that long at each turn, then goes on by
    itself; with 0 it never waits (the web page is left unopened, the prompt's input is empty)."""
    from sgim_nodes.bag.reader import load_run, read_messages

    movements, period = 100, 50
    child = ros_processes.start(f"wait-{teacher}", [
        RUN, "sgim-d", "--seed", "6", "--movements", str(movements), "--eval-every", "0",
        "--demonstration-period", str(period), "--teacher", teacher, "--wait-for-teacher", wait,
        *(["--web-port", "0"] if teacher == "web" else []), "--runs-dir", str(tmp_path),
        "--name", "run", "--domain", str(ros_domain), "--quiet", "--timeout", "300"],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output, _ = child.communicate(timeout=330)
    assert child.returncode == 0, output[-3000:]

    from sgim_nodes.graph.processes import node_log

    arbiter_log = node_log(tmp_path / "run" / "logs", "social_interaction").read_text()
    turns = re.findall(r"teacher's turn at movement (\d+): (.+)", arbiter_log)
    states = [msg for topic, _, msg in read_messages(tmp_path / "run" / "bag")
              if topic == "/pace_state"]
    waited = sorted({s.movement_index for s in states if s.waiting_for_teacher})
    if wait == "0":
        assert turns == [] and waited == []
        assert all(s.teacher_period == 0 and not s.paused for s in states)
    else:
        assert turns == [(str(i), f"no demonstration within {wait} s") for i in (0, period)]
        assert waited == [0, period]
        assert {s.wait_seconds for s in states} == {float(wait)}
    run = load_run(tmp_path / "run" / "bag")
    assert [m.index for m in run.movements] == list(range(1, movements + 1))
    assert not run.demonstrations
