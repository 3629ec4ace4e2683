"""The web teacher without ROS: the page's commands, its incremental state, its HTTP rules."""

from __future__ import annotations

import http.client
import itertools
import json
import re
import socket
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from sgim_nodes.view.picture import LivePicture
from teacher.human_commands import CommandError, NoneThere, PaceRequest
from teacher.human_decisions import ExecuteFirst, LearnerState, SendDemonstration, TeachingLibrary
from teacher.web.app import WebTeacher
from teacher.web.server import Api, Refused, TeacherServer

A = 24
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5], [0.5, -0.5]])
ACTIONS = np.array([np.full(A, 0.1 * (i + 1)) for i in range(len(OUTCOMES))])


@pytest.fixture
def app() -> WebTeacher:
    library = TeachingLibrary(ACTIONS, OUTCOMES, 0.05)
    return WebTeacher(library, LivePicture(library.teacher), LearnerState(A))


def feed(app: WebTeacher, index: int, outcome, process: int = 0) -> None:
    app.picture.add_movement(index, process, bool(outcome), outcome, [0.1, 0.1])
    app.learner.add_movement(index, bool(outcome), np.full(A, -0.3), outcome)


def test_state_sends_only_what_changed(app):
    feed(app, 1, [0.5, 0.51])
    feed(app, 2, [])
    first = app.state()
    assert first["landings"] == {"from": 0, "x": [0.5], "y": [0.51], "p": [0]}
    assert first["count"] == 2 and first["failed"] == 1
    assert first["teaching"]["reached"] == [False, True, False, False]  # the teacher's rule
    feed(app, 3, [-0.2, -0.2], process=2)
    second = app.state(landings=1, evaluations=0, regions=first["regions"]["version"],
                       teaching=first["teaching"]["version"], log=0)
    assert second["landings"] == {"from": 1, "x": [-0.2], "y": [-0.2], "p": [2]}
    assert "regions" not in second and "teaching" not in second
    assert second["goal"] == (0.1, 0.1)


def test_page_commands_become_the_terminals_decisions(app):
    assert isinstance(app.decide({"command": "teach", "index": 2}), SendDemonstration)
    offer = app.decide({"command": "offer", "x": 0.45, "y": 0.5})
    assert offer["ok"] and offer["offer"]["teaching_set_index"] == 1
    sent = app.decide({"command": "confirm", "offer": offer["offer"]["id"]})
    assert np.array_equal(sent.action, ACTIONS[1])
    pasted = app.decide({"command": "action", "text": "[" + ", ".join(["0.25"] * A) + "]"})
    assert isinstance(pasted, ExecuteFirst) and np.allclose(pasted.action, 0.25)
    assert app.decide({"command": "pace", "what": "step", "steps": 4}) == PaceRequest("step", 4)
    assert app.decide({"command": "none"}) == NoneThere()  # SGIM-ACTS asked: nothing there
    assert app.state()["expert"] == ""  # the page shows its "none there" box only when asked


def test_the_web_expert_answers_the_oldest_request_and_refuses_when_none_is_open():
    """teacher/web_expert.py without ROS: what each answer says, and the refusal."""
    from sgim_msgs.msg import HelpRequest
    from teacher.web_expert import WebExpert

    expert = WebExpert.__new__(WebExpert)  # its ROS half (subscriptions) is the node's
    expert.name, expert.source, expert.open, expert.answered = "web", "expert:web", [], set()
    with pytest.raises(CommandError, match="not asked you anything"):
        expert.none_there(None)
    expert.open = [HelpRequest(index=3, movement_index=40, goal=[0.1, 0.2], teacher="web",
                               content="goal-only"),
                   HelpRequest(index=4, movement_index=40, goal=[0.3, 0.2], teacher="web",
                               content="means-and-goal")]
    emulation = expert.answer(None, 7, ACTIONS[1], [0.5, 0.5], 1)
    assert (emulation.help_request, emulation.movement_index, list(emulation.action),
            list(emulation.outcome), emulation.source) == (3, 40, [], [0.5, 0.5], "expert:web")
    empty = expert.none_there(None)
    assert empty.help_request == 4 and not len(empty.action) and not len(empty.outcome)
    assert expert.answered == {3, 4} and not expert.open


@pytest.mark.parametrize(("body", "words"), [
    ("teach 1", "must be a JSON object"),
    ({"command": "fly"}, "unknown command 'fly'"),
    ({"command": "teach", "index": "1"}, "needs a teaching-set index"),
    ({"command": "teach", "index": 7}, "no teaching-set entry 7"),
    ({"command": "offer", "x": 2, "y": 0}, "goal x = 2 is outside [-1, 1]"),
    ({"command": "offer", "x": None, "y": 0}, "goal x is None, not a number"),
    ({"command": "confirm", "offer": 99}, "no offer 99"),
    ({"command": "action", "text": "0.1 0.2"}, "has 2 numbers, 24 are needed"),
    ({"command": "action", "text": " ".join(["inf"] * A)}, "is infinite"),
    ({"command": "pace", "what": "faster"}, "unknown pace command"),
    ({"command": "pace", "what": "step", "steps": 0}, "from 1 to 100000"),
])
def test_bad_commands_are_refused_with_a_reason(app, body, words):
    with pytest.raises(CommandError, match=None) as refused:
        app.decide(body)
    assert words in str(refused.value)


def test_no_demonstration_once_the_budget_is_spent_or_the_run_over(app):
    app.learner.total = 3
    feed(app, 3, [0.2, 0.2])
    for body in ({"command": "teach", "index": 0}, {"command": "offer", "x": 0, "y": 0},
                 {"command": "action", "text": " ".join(["0"] * A)}):
        with pytest.raises(CommandError, match="the movement budget is spent"):
            app.decide(body)
    app.learner.run_over = "finished"
    with pytest.raises(CommandError, match=r"the run is over \(finished\)"):
        app.decide({"command": "teach", "index": 0})


class FakeApi(Api):
    def state(self, query):
        return {"query": query}

    def command(self, body):
        return {"ok": True, "echo": body}

    def legend(self):
        return {}

    def image(self, name):
        return None


def _request(url, data=None, headers=None):
    request = urllib.request.Request(url, data=data, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, reply.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def test_the_server_refuses_what_a_foreign_page_could_send():
    with pytest.raises(Refused, match="needs an access token"):
        TeacherServer("0.0.0.0", 0, "", FakeApi())
    server = TeacherServer("127.0.0.1", 0, "a-token-of-sixteen+", FakeApi())
    server.start()
    try:
        base = f"http://127.0.0.1:{server.port}"
        assert server.url == f"{base}/?token=a-token-of-sixteen+"
        assert _request(f"{base}/api/state")[0] == 401
        status, body = _request(f"{base}/api/state?landings=5&token=a-token-of-sixteen%2B")
        assert status == 200 and json.loads(body)["query"]["landings"] == 5
        token = {"X-Teacher-Token": "a-token-of-sixteen+"}
        assert _request(f"{base}/", headers=token)[0] == 200
        assert _request(f"{base}/static/../server.py", headers=token)[0] == 404
        assert _request(f"{base}/api/state", headers={**token, "Host": "evil.example"})[0] == 403
        command = b'{"command": "pace", "what": "pause"}'
        assert _request(f"{base}/api/command", command, token)[0] == 403  # no X-Teacher
        status, body = _request(f"{base}/api/command", b"{nope", {**token, "X-Teacher": "1"})
        assert status == 400 and b"not JSON" in body
        status, body = _request(f"{base}/api/command", command, {**token, "X-Teacher": "1"})
        assert status == 200 and json.loads(body)["echo"]["what"] == "pause"
        # On one kept-alive connection a refused command leaves nothing behind for the next.
        connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
        for headers, expected in (({}, 403), ({"X-Teacher": "1"}, 200)):
            connection.request("POST", "/api/command", command, {**token, **headers})
            reply = connection.getresponse()
            assert reply.status == expected
            assert reply.getheader("Content-Type") == "application/json"
            reply.read()
        connection.close()
        assert _request(f"{base}/cast.gif", headers=token)[0] == 404
    finally:
        server.stop()


def test_on_every_interface_the_token_is_the_key_whatever_name_the_teacher_uses():
    """A teacher on another machine reaches the server by this machine's name or address:
    any Host is accepted there, with the token and only with it."""
    server = TeacherServer("0.0.0.0", 0, "a-token-of-sixteen+", FakeApi())
    server.start()
    try:
        assert server.url == (f"http://{socket.gethostname()}:{server.port}/"
                              "?token=a-token-of-sixteen+")
        base = f"http://127.0.0.1:{server.port}"
        for name in ("teacher-pc.example", "192.0.2.7", socket.gethostname()):
            host = {"Host": f"{name}:{server.port}"}
            assert _request(f"{base}/api/state", headers=host)[0] == 401
            status, _ = _request(f"{base}/api/state",
                                 headers={**host, "X-Teacher-Token": "a-token-of-sixteen+"})
            assert status == 200
    finally:
        server.stop()


# --- issue 31: the page as a person uses it -------------------------------------------------

def key(n: int) -> str:
    return f"test-key-{n:04d}"


class Sender:
    """The node's side of a command, without ROS: a demonstration is published after
    ``delay`` seconds and counted."""

    def __init__(self, app: WebTeacher, delay: float = 0.0) -> None:
        self.app, self.delay, self.sent = app, delay, []
        self.lock = threading.Lock()

    def __call__(self, decision):
        time.sleep(self.delay)
        if not isinstance(decision, SendDemonstration):
            return {"ok": True, "message": "done"}
        with self.app.lock:
            self.app.learner.demonstrations += 1
            number, at = self.app.learner.demonstrations, self.app.learner.movement_count
            self.app.demonstration_sent(number, at)
        with self.lock:
            self.sent.append(decision)
        return {"ok": True, "message": f"sent demonstration {number}", "demonstration": number,
                "movement": at}


def test_a_demonstration_needs_a_key_and_a_repeated_request_is_refused(app):
    send = Sender(app)
    no_key = app.command({"command": "teach", "index": 0}, send)
    assert not no_key["ok"] and "needs a 'key'" in no_key["message"]
    first = app.command({"command": "teach", "index": 0, "key": key(1)}, send)
    assert first["ok"]
    again = app.command({"command": "teach", "index": 0, "key": key(1)}, send)
    assert not again["ok"]
    assert again["message"] == (f"repeated request ignored (key {key(1)}): it was answered: "
                                "sent demonstration 1")
    assert len(send.sent) == 1
    assert "refused: repeated request ignored" in app.log[-1][2]  # in the page's log too


def test_twenty_simultaneous_clicks_give_one_demonstration(app):
    """20 requests at once (a person's repeated clicks, other tabs): one demonstration; the
    others are refused while it is on its way, then while the learner imitates it (each new
    one cut the imitation under way short)."""
    send = Sender(app, delay=0.05)
    barrier = threading.Barrier(20)
    answers = []

    def click(n: int) -> None:
        barrier.wait()
        answers.append(app.command({"command": "teach", "index": 1, "key": key(n)}, send))

    threads = [threading.Thread(target=click, args=(n,)) for n in range(20)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(send.sent) == 1 and sum(a["ok"] for a in answers) == 1
    refusals = {a["message"].split(":")[0] for a in answers if not a["ok"]}
    assert refusals <= {"a demonstration is on its way",
                        "demonstration 1 (sent at movement 0) is not imitated to its end yet, "
                        "and another one now would cut it short"}, refusals


def test_the_next_demonstration_waits_until_the_imitation_is_over(app):
    from sgim_nodes.core.environment import PROCESS_CODES

    imitation, own = PROCESS_CODES["imitation"], PROCESS_CODES["goal_directed"]
    send = Sender(app)

    def move(index: int, process: int) -> None:  # as the node hears a movement
        feed(app, index, [0.2, 0.2], process)
        app.movement_seen(index, process)

    move(10, own)
    assert app.command({"command": "teach", "index": 0, "key": key(1)}, send)["ok"]
    for n, (index, process) in enumerate([(11, own), (12, imitation), (13, imitation)],
                                         start=2):
        move(index, process)  # the job it cancelled, then its imitation
        refused = app.command({"command": "teach", "index": 2, "key": key(n)}, send)
        assert "not imitated to its end yet" in refused["message"]
    move(14, own)  # the learner is back to its own goals
    assert app.command({"command": "teach", "index": 2, "key": key(9)}, send)["ok"]
    # A demonstration the arbiter refused is never imitated: two movements of its own end it.
    move(15, own)
    assert not app.command({"command": "teach", "index": 3, "key": key(10)}, send)["ok"]
    move(16, own)
    assert app.command({"command": "teach", "index": 3, "key": key(11)}, send)["ok"]
    assert [d.teaching_set_index for d in send.sent] == [0, 2, 3]


@pytest.mark.parametrize("body", [
    {"command": "confirm", "offer": [1]}, {"command": "confirm", "offer": {"a": 1}},
    {"command": "teach", "index": [1]}, {"command": ["teach"]}, {"command": {"x": 1}},
    {"command": "pace", "what": ["step"]}, {"command": "pace", "what": "step", "steps": [2]},
    {"command": "offer", "x": 10**400, "y": 0}, {"command": "offer", "x": [0.1], "y": 0}])
def test_a_command_of_the_wrong_types_is_refused_not_a_crash(app, body):
    """{"command": "confirm", "offer": [1]} raised TypeError (unhashable) in the handler."""
    body = {**body, "key": key(1)}
    answer = app.command(body, Sender(app))
    assert answer["ok"] is False and answer["message"]


def test_an_offer_names_its_cost_lower_is_better(app):
    offer = app.decide({"command": "offer", "x": 0.45, "y": 0.5})
    text = offer["offer"]["text"]
    assert "reliability" not in text
    assert re.search(r"cost \d\.\d{3} = distance \+ [\d.]+ x variance of its neighbours' "
                     r"actions, lower is better", text), text


def _lab(rgb) -> np.ndarray:
    """CIE L*a*b* (D65) of an sRGB colour, to compare colours as eyes do."""
    c = np.asarray(rgb, dtype=float) / 255
    c = np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                    [0.0193, 0.1192, 0.9505]]) @ c / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def delta_e(a, b) -> float:
    return float(np.linalg.norm(_lab(a) - _lab(b)))


def test_the_legend_offers_no_process_that_never_lands_and_its_colours_are_distinct():
    """The old legend's 'demonstration' landing colour was never drawn (a demonstration's
    measuring cast is no movement) and almost the red of unreached goals."""
    legend = WebTeacher.legend()
    names = {p["name"] for p in legend["processes"].values()}
    assert "demonstration" not in names and {"own goal", "exploration", "imitation"} <= names
    colours = {**{p["name"]: p["rgb"] for p in legend["processes"].values()},
               **legend["marks"], **legend["lake"]}
    close = [(a, b, round(delta_e(colours[a], colours[b]), 1))
             for a, b in itertools.combinations(colours, 2)
             if delta_e(colours[a], colours[b]) < 20]
    assert not close, close


def test_the_page_names_the_runs_learner_and_the_metres_its_axes_show(app):
    """The title said SGIM-D for an SGIM-ACTS run; the map had no scale."""
    from sim_bridge.scaling import outcome_to_world

    assert app.state()["learner_title"] == ""  # no run said its learner yet
    for learner, title in (("sgim-acts", "SGIM-ACTS"), ("sgim-d", "SGIM-D"),
                           ("saggriac", "SAGG-RIAC"), ("someday", "someday")):
        app.picture.set_status(learner, 0, 100, "running", "started")
        assert app.state()["learner_title"] == title
    space = WebTeacher.legend()["space"]
    assert space["unit"] == "m"
    low, high = outcome_to_world(np.array([[-1.0, -1.0], [1.0, 1.0]]))
    assert space["box"] == [low[0], high[0], low[1], high[1]]


def test_land_and_water_stay_apart_under_any_interest_shading():
    """Under the page's shading (teacher.js SHADE_ALPHA) of any interest colour, the lake's
    two colours differ as much as two distinct marks (the old pale pair dropped to 13)."""
    from sgim_nodes.view.picture import interest_colour

    js = (Path(__file__).resolve().parents[2] / "teacher" / "teacher" / "web" / "static"
          / "teacher.js").read_text()
    alpha = float(re.search(r"const SHADE_ALPHA = ([\d.]+);", js).group(1))
    legend = WebTeacher.legend()["lake"]
    for f in np.linspace(0, 1, 11):
        shade = np.array(interest_colour(f))
        water, land = ((1 - alpha) * np.array(legend[k]) + alpha * shade for k in ("water", "land"))
        assert delta_e(water, land) >= 20, (f, water, land)


def test_the_page_lingers_after_the_run_only_for_someone_looking(app, monkeypatch):
    from teacher.web import app as app_module

    clock = [1000.0]
    monkeypatch.setattr(app_module.time, "monotonic", lambda: clock[0])
    with pytest.raises(CommandError, match="the run is still going"):
        app.decide({"command": "close"})
    assert app.run_ended(60.0) is False  # nobody ever looked: ends with the run, as before
    watched = WebTeacher(app.library, LivePicture(app.library.teacher), LearnerState(A))
    watched.state()  # a page asked
    clock[0] += 30.0
    assert watched.run_ended(0.0) is False  # linger 0: today's behaviour
    watched = WebTeacher(app.library, LivePicture(app.library.teacher), LearnerState(A))
    watched.state()
    clock[0] += 30.0
    assert watched.run_ended(60.0) is True
    assert watched.state()["linger"] == {"left": 60.0, "closed": False}
    clock[0] += 59.0
    assert not watched.linger_ended()
    clock[0] += 1.0
    assert watched.linger_ended()  # its time ran out
    closing = WebTeacher(app.library, LivePicture(app.library.teacher), LearnerState(A))
    closing.state()
    assert closing.run_ended(600.0)
    closing.learner.run_over = "finished"
    assert closing.decide({"command": "close"})["ok"]  # the person closed it
    assert closing.linger_ended() and closing.state()["linger"]["closed"]
    late = WebTeacher(app.library, LivePicture(app.library.teacher), LearnerState(A))
    late.state()
    clock[0] += 91.0  # the page was closed long before the end
    assert late.run_ended(600.0) is False
