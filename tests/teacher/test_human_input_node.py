"""The human_input node driven through its prompt, over ROS, as a person would at a terminal.

The node reads a pipe here (a pseudo-terminal in the last test): the test types lines, reads
what it prints and checks the demonstrations it publishes. Until the lead adds the console
script it is started with `python -m teacher.human_input_node`.
"""

from __future__ import annotations

import contextlib
import os
import pty
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

from tests.conftest import PYTHON
from tests.ros.graph_client import GraphClient

pytestmark = pytest.mark.ros

A = 24
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5], [0.5, -0.5]])
ACTIONS = np.array([np.full(A, 0.1 * (i + 1)) for i in range(len(OUTCOMES))])
PROMPT = "human> "


class Terminal:
    """The node's stdin and stdout: type lines, wait for what it prints."""

    def __init__(self, child: subprocess.Popen, client: GraphClient,
                 tty: int | None = None) -> None:
        """``tty``: the master side of the pseudo-terminal the node reads and writes, if any."""
        self.child, self.client, self.tty = child, client, tty
        self.text = ""
        self._lock = threading.Lock()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        fd = self.child.stdout.fileno() if self.tty is None else self.tty
        with contextlib.suppress(OSError):  # a pseudo-terminal whose node ended: EIO
            while chunk := os.read(fd, 4096):
                with self._lock:
                    self.text += chunk.decode(errors="replace")

    def output(self, start: int = 0) -> str:
        with self._lock:
            return self.text[start:]

    def wait_for(self, text: str, start: int = 0, timeout: float = 30.0) -> str:
        """Spin the test node (its service may be called) until `text` is printed."""
        found = self.client.spin_until(lambda: text in self.output(start), timeout)
        assert found, f"{text!r} never printed; output so far:\n{self.output()}"
        out = self.output(start)
        return out[: out.index(text)]

    def type(self, line: str, end: str = "\n") -> int:
        """Type a line (or keys, with end=""); returns where the reply starts in the output."""
        start = len(self.output())
        if self.tty is not None:
            os.write(self.tty, f"{line}{end}".encode())
        else:
            self.child.stdin.write(f"{line}{end}".encode())
            self.child.stdin.flush()
        return start

    def command(self, line: str) -> str:
        """Type a line; the node's reply, up to its next prompt."""
        return self.wait_for(PROMPT, self.type(line))

    def exit_code(self, timeout: float = 20.0) -> int:
        deadline = time.monotonic() + timeout
        while self.child.poll() is None and time.monotonic() < deadline:
            self.client.spin_for(0.05)
        assert self.child.poll() is not None, f"node did not exit:\n{self.output()}"
        self._reader.join(timeout=5)
        return self.child.returncode


@pytest.fixture
def teaching_file(tmp_path):
    path = tmp_path / "teaching_set.npz"
    np.savez(path, actions=ACTIONS, outcomes=OUTCOMES, spread=np.zeros(len(OUTCOMES)))
    return path


@pytest.fixture
def client(rclpy_context):
    c = GraphClient(rclpy_context)
    yield c
    c.close()


def _start(ros_processes, tmp_path, *params: str, name: str = "human_input"):
    argv = [PYTHON, "-m", "teacher.human_input_node", "--ros-args"]
    for p in params:
        argv += ["-p", p]
    return ros_processes.start(name, argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, cwd=tmp_path)


def _movement(index: int, action, outcome):
    from sgim_msgs.msg import Movement

    status = Movement.STATUS_OK if outcome else Movement.STATUS_NO_CONTACT
    return Movement(index=index, process=Movement.PROCESS_GOAL_DIRECTED, status=status,
                    action=[float(v) for v in action], outcome=[float(v) for v in outcome])


def test_list_teach_goal_and_bad_input_through_the_prompt(ros_processes, client, tmp_path,
                                                          teaching_file):
    from sgim_msgs.msg import Demonstration, Evaluation, Movement, RunStatus
    from sgim_ros import qos
    from teacher.human_commands import GoalPoint
    from teacher.human_decisions import LearnerState, TeachingLibrary

    demos = client.capture(Demonstration, "/demonstrations", qos.RECORDS)
    movements = client.node.create_publisher(Movement, "/movements", qos.RECORDS)
    evaluations = client.node.create_publisher(Evaluation, "/evaluations", qos.RECORDS)
    child = _start(ros_processes, tmp_path, f"teaching_set:={teaching_file}")
    term = Terminal(child, client)
    term.wait_for(PROMPT)
    assert "4 teaching-set entries" in term.output()
    assert client.spin_until(lambda: client.heard_by("/movements", "human_input")
                             and client.heard_by("/evaluations", "human_input"))

    learner = np.full(A, -0.3)
    sent = [_movement(1, learner, [0.5, 0.52]),  # reaches teaching entry 1
            _movement(2, learner, []),  # a failed cast: counted, not a reached outcome
            _movement(3, learner, [-0.2, -0.2])]
    for m in sent:
        movements.publish(m)
    evaluations.publish(Evaluation(movement_index=3, mean_distance=0.321, outcome_size=2,
                                   goals=[0.0, 0.0], reached=[0.1, 0.1], distances=[0.321]))
    # Poll until the node has heard everything and sees the test's subscription.
    for _ in range(100):
        status = term.command("status")
        if ("movements: 3" in status and "0.3210" in status
                and "listening to demonstrations: 1" in status):
            break
        client.spin_for(0.1)
    else:
        pytest.fail(f"the node never heard the movements:\n{term.output()}")

    listed = term.command("list").splitlines()
    assert "3 of 4 teaching goals not reached within 0.07:" in listed  # 1 x outcome noise
    numbered = [int(line.split(":")[0]) for line in listed if line.startswith("  ")]
    assert numbered == [0, 2, 3]

    reply = term.command("teach 0")
    assert "sent demonstration 1 at movement 3" in reply and "teaching-set entry 0" in reply
    assert client.spin_until(lambda: len(demos) == 1)
    d = demos[0]
    assert d.source == "human" and d.teaching_set_index == 0 and d.index == 1
    assert d.movement_index == 3
    assert np.array_equal(d.action, ACTIONS[0]) and np.array_equal(d.outcome, OUTCOMES[0])

    for bad, message in [("fly", "error: unknown command 'fly'"),
                         ("teach 9", "error: no teaching-set entry 9: entries are 0 to 3"),
                         ("goal 0.1", "error: 'goal' needs 2 numbers"),
                         ("goal 0.1 nan", "error: goal Y is NaN"),
                         ("goal 1.5 0", "error: goal X = 1.5 is outside [-1, 1]"),
                         ("yaml missing.yaml", "error: no such file: missing.yaml")]:
        assert message in term.command(bad)
    (tmp_path / "no_outcome.yaml").write_text(str([0.0] * A))
    # No execute_action server in this test and no outcome in the file: refused, clearly.
    assert "start sim_bridge, or add 'outcome: [x, y]'" in term.command("yaml no_outcome.yaml")

    # 'goal' only offers the library's pair, saying how far it lands; 'send' demonstrates it.
    assert "error: no offer to send: 'goal X Y' makes one" in term.command("send")
    reply = term.command("goal 0.1 0.2")
    assert "\noffer: for goal (+0.100, +0.200): " in reply
    assert "from the goal" in reply and "type 'send' to demonstrate it" in reply
    client.spin_for(0.3)
    assert len(demos) == 1  # nothing sent yet
    assert "sent demonstration 2 at movement 3" in term.command("send")
    assert client.spin_until(lambda: len(demos) == 2)
    state = LearnerState(A)
    for m in sent:
        state.add_movement(m.index, len(m.outcome) == 2, m.action, m.outcome)
    expected = TeachingLibrary(ACTIONS, OUTCOMES, 0.07).decide(GoalPoint((0.1, 0.2)), state)
    d = demos[1]
    assert d.teaching_set_index == expected.teaching_set_index and d.index == 2
    assert np.array_equal(d.action, expected.action)
    assert np.array_equal(d.outcome, expected.outcome)
    assert expected.text in reply  # the reply says which pair was taken

    # Among a lone learner movement and the teaching set, the exact pair wins and is named.
    reply = term.command("goal -0.2 -0.2")
    assert "the action of learner movement 3, outcome (-0.200, -0.200)" in reply
    assert "sent demonstration 3 at movement 3" in term.command("send")
    assert client.spin_until(lambda: len(demos) == 3)
    assert "error: no offer to send" in term.command("send")  # an offer is sent once
    assert demos[2].teaching_set_index == -1 and np.array_equal(demos[2].action, learner)

    # The budget is spent: the arbiter's refusal of a late demonstration is a warning, and
    # the prompt refuses to send another one, saying why.
    status = client.node.create_publisher(RunStatus, "/run_status", qos.RECORDS)
    assert client.spin_until(lambda: client.heard_by("/run_status", "human_input"))
    status.publish(RunStatus(state=RunStatus.STATE_RUNNING, movement_index=3,
                             total_movements=3, message="demonstration 4 (human) refused: "
                             "the movement budget is spent"))
    term.wait_for("warning: demonstration 4 (human) refused: the movement budget is spent")
    assert ("error: the movement budget is spent (3/3): the learner takes no more "
            "demonstrations") in term.command("teach 2")

    start = term.type("quit")
    assert term.exit_code() == 0
    assert term.output(start).strip().endswith("bye")
    client.spin_for(0.3)
    assert len(demos) == 3  # bad input sent nothing
    assert "Traceback" not in term.output()


def test_yaml_action_is_measured_by_execute_action_then_end_of_input(ros_processes, client,
                                                                     tmp_path, teaching_file):
    from sgim_msgs.msg import Demonstration, Movement
    from sgim_msgs.srv import ExecuteAction
    from sgim_ros import qos

    requests = []
    answers = [(Movement.STATUS_OK, [0.25, -0.5], ""),
               (Movement.STATUS_NO_CONTACT, [], "the hook never touched the water")]

    def execute(request, response):
        requests.append(request)
        response.status, response.outcome, response.message = answers[len(requests) - 1]
        return response

    client.node.create_service(ExecuteAction, "/execute_action", execute)
    demos = client.capture(Demonstration, "/demonstrations", qos.RECORDS)
    child = _start(ros_processes, tmp_path, f"teaching_set:={teaching_file}")
    term = Terminal(child, client)
    term.wait_for(PROMPT)
    for _ in range(100):
        if "listening to demonstrations: 1" in term.command("status"):
            break
        client.spin_for(0.1)

    action = [round(-1 + 2 * i / 23, 4) for i in range(A)]
    (tmp_path / "demo.yaml").write_text(f"# a person's cast\naction: {action}\n")
    reply = term.command("yaml demo.yaml")
    assert "executed: outcome (+0.250, -0.500)" in reply and "sent demonstration 1" in reply
    assert client.spin_until(lambda: len(demos) == 1)
    assert demos[0].outcome.tolist() == [0.25, -0.5] and demos[0].teaching_set_index == -1
    assert np.allclose(demos[0].action, action)
    r = requests[0]
    assert not r.record and r.movement_index == 0 and np.allclose(r.action, action)

    assert "did not land (the hook never touched the water): nothing sent" in term.command(
        "yaml demo.yaml")
    (tmp_path / "short.yaml").write_text("[0.1, 0.2]")
    assert "action has 2 values, 24 are needed" in term.command("yaml short.yaml")

    child.stdin.close()  # end of input, as `node < commands.txt` would give
    assert term.exit_code() == 0
    assert "end of input: bye" in term.output()
    client.spin_for(0.3)
    assert len(demos) == 1 and len(requests) == 2


def test_bad_parameters_and_ctrl_c(ros_processes, client, tmp_path, teaching_file):
    for params, words in [(["tolerance_noise:=-0.5"], ["tolerance_noise", ">= 0"]),
                          (["outcome_noise:=abc"], ["outcome_noise", "type float"]),
                          (["execute_timeout:=0.0"], ["execute_timeout", "> 0"]),
                          ([f"teaching_set:={tmp_path / 'nope.npz'}"], ["teaching_set", "nope"])]:
        child = _start(ros_processes, tmp_path, *params, name="human_input_bad")
        output, _ = child.communicate(timeout=60)
        assert child.returncode == 2, output.decode()
        for w in words:
            assert w in output.decode()

    child = _start(ros_processes, tmp_path, f"teaching_set:={teaching_file}", name="ctrl_c")
    term = Terminal(child, client)
    term.wait_for(PROMPT)
    os.killpg(child.pid, signal.SIGINT)
    assert term.exit_code() == 0
    assert "bye" in term.output() and "Traceback" not in term.output()


UP, LEFT, ENTER = "\x1b[A", "\x1b[D", "\r"


def test_a_terminal_gets_line_editing_history_and_news_above_the_prompt(
        ros_processes, client, tmp_path, teaching_file):
    """On a (pseudo-)terminal: readline's arrows and a history kept across sessions, a line
    from the graph printed above the prompt without losing what is being typed, and the
    prompt redrawn with a new evaluation's error."""
    from sgim_msgs.msg import Evaluation, RunStatus
    from sgim_ros import qos

    history = tmp_path / "history"
    history.write_text("list\n")  # what a previous session typed
    ros_processes.env = {**ros_processes.env, "SGIM_TEACHER_HISTORY": str(history),
                         "TERM": "xterm"}
    status = client.node.create_publisher(RunStatus, "/run_status", qos.RECORDS)
    master, slave = pty.openpty()
    try:
        child = ros_processes.start(
            "human_input_tty", [PYTHON, "-m", "teacher.human_input_node", "--ros-args", "-p",
                                f"teaching_set:={teaching_file}"],
            stdin=slave, stdout=slave, stderr=slave, cwd=tmp_path)
    finally:
        os.close(slave)
    try:
        term = Terminal(child, client, tty=master)
        term.wait_for(PROMPT)
        # Up recalls the previous session's line; Enter runs it.
        reply = term.wait_for(PROMPT, term.type(UP, end=ENTER))
        assert "4 of 4 teaching goals not reached" in reply
        # Left arrows move in the line: "sttus" corrected to "status".
        reply = term.wait_for(PROMPT, term.type("sttus" + 3 * LEFT + "a", end=ENTER))
        assert "movements: 0" in reply
        assert "^[[" not in term.output()  # no arrow key printed as garbage
        # News from the run while "li" is half typed: above the prompt, which is redrawn with
        # the typed text, so finishing the line still runs "list".
        assert client.spin_until(lambda: client.heard_by("/run_status", "human_input"))
        start = term.type("li", end="")
        term.wait_for("li", start)
        status.publish(RunStatus(state=RunStatus.STATE_RUNNING, movement_index=5,
                                 total_movements=10, message="running"))
        before = term.wait_for("progress: movement 5/10 (50 %)", start)
        term.wait_for(f"[movements 5/10 | error - | demos 0] {PROMPT}li", start + len(before))
        assert before.endswith("\r\x1b[K")  # the line being typed was cleared first
        # A new evaluation redraws the prompt in place, typed text kept: its error is the
        # latest, not the one of when the prompt was drawn (it stayed 0.523 all run).
        evaluations = client.node.create_publisher(Evaluation, "/evaluations", qos.RECORDS)
        assert client.spin_until(lambda: client.heard_by("/evaluations", "human_input"))
        start = len(term.output())
        evaluations.publish(Evaluation(movement_index=5, mean_distance=0.321, outcome_size=2,
                                       goals=[0.0, 0.0], reached=[0.1, 0.1],
                                       distances=[0.321]))
        term.wait_for(f"\r\x1b[K[movements 5/10 | error 0.321 | demos 0] {PROMPT}li", start)
        reply = term.wait_for(PROMPT, term.type("st", end=ENTER))
        assert "4 of 4 teaching goals not reached" in reply
        start = term.type("quit", end=ENTER)
        assert term.exit_code() == 0, term.output()
        assert "bye" in term.output(start) and "Traceback" not in term.output()
    finally:
        os.close(master)
    lines = history.read_text().splitlines()  # kept for the next session
    assert lines[0] == "list" and lines[-3:] == ["status", "list", "quit"]


PIPE_INTERRUPT = """
import _thread, os, sys, threading
{reader}
threading.Timer(0.5, _thread.interrupt_main).start()
try:
    read("human> ")
except KeyboardInterrupt:
    print("interrupted")
"""


@pytest.mark.parametrize(("reader", "interrupted"), [
    ("from teacher.prompt_loop import PipeLines\n"
     "read = PipeLines(os.fdopen(os.pipe()[0]), sys.stdout).input", True),
    # The control: input() blocked in read() never sees an interrupt that is flagged but does
    # not interrupt the read (what a SIGINT landing just before the read did).
    ("sys.stdin = os.fdopen(os.pipe()[0])\nread = input", False),
])
def test_an_interrupt_that_lands_before_the_read_still_ends_the_prompt(reader, interrupted):
    """_thread.interrupt_main flags SIGINT without interrupting any system call: exactly the
    state a SIGINT leaves when it lands between the prompt's write and the read."""
    child = subprocess.Popen([PYTHON, "-c", PIPE_INTERRUPT.format(reader=reader)],
                             stdout=subprocess.PIPE, text=True)
    try:
        output, _ = child.communicate(timeout=20 if interrupted else 3)
    except subprocess.TimeoutExpired:
        child.kill()
        output, _ = child.communicate()
    assert ("interrupted" in output) == interrupted, output
