"""The web teacher without ROS: the page's commands, its incremental state, its HTTP rules."""

from __future__ import annotations

import http.client
import json
import socket
import urllib.error
import urllib.request

import numpy as np
import pytest

from sgim_nodes.view.picture import LivePicture
from teacher.human_commands import CommandError, PaceRequest
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
