"""No request can crash the web teacher's server: property-based tests (Hypothesis) over every
route and command body, without ROS.

The server runs with the page's real logic (WebTeacher: state, legend, the commands and their
keys), the node's ROS side replaced by an answer made here. Each example is one TCP
connection, written raw (so a request may be as broken as any client can make it) and then
half-closed; what comes back must be an HTTP/1.x answer whose JSON says ok or why not (the
page's files and pictures aside), never a 500, and the server must log no error and print
no traceback. Examples are derandomised: the same cases every run (the counts of what they
got are printed with -s).
"""

from __future__ import annotations

import collections
import contextlib
import http.client
import io
import json
import logging
import socket
from urllib.parse import quote

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sgim_nodes.view.picture import Leaf, LivePicture
from teacher.human_commands import PaceRequest
from teacher.human_decisions import ExecuteFirst, LearnerState, SendDemonstration, TeachingLibrary
from teacher.web.app import WebTeacher
from teacher.web.server import STATIC_FILES, Api, TeacherServer

A = 24
OUTCOMES = np.array([[0.0, 0.0], [0.5, 0.5], [-0.5, 0.5], [0.5, -0.5]])
ACTIONS = np.array([np.full(A, 0.1 * (i + 1)) for i in range(len(OUTCOMES))])
TOKEN = "fuzz-token-0123456789_abc"
FUZZ = settings(max_examples=400, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.function_scoped_fixture])
TRIED: collections.Counter = collections.Counter()  # (test, what it got) -> cases


def fresh_app() -> WebTeacher:
    library = TeachingLibrary(ACTIONS, OUTCOMES, 0.05)
    app = WebTeacher(library, LivePicture(library.teacher), LearnerState(A))
    for i, outcome in enumerate(([0.5, 0.51], [], [-0.2, -0.2]), start=1):
        app.picture.add_movement(i, 0, bool(outcome), outcome, [0.1, 0.1])
        app.learner.add_movement(i, bool(outcome), np.full(A, -0.3), outcome)
    app.picture.set_regions([Leaf((-1.0, -1.0), (0.0, 1.0), 0.2),
                             Leaf((0.0, -1.0), (1.0, 1.0), 0.5)])
    app.picture.add_evaluation(0, 0.5)
    return app


class PageApi(Api):
    """What the node answers, its ROS side replaced: a demonstration is 'sent' at once."""

    def __init__(self) -> None:
        self.app = fresh_app()

    def state(self, query):
        return self.app.state(**query)

    def legend(self):
        return self.app.legend()

    def image(self, name):
        return b"\x89PNG\r\n\x1a\n" if name == "lake.png" else None

    def command(self, body):
        return self.app.command(body, self.carry_out)

    def carry_out(self, decision):
        if isinstance(decision, SendDemonstration):
            with self.app.lock:
                self.app.learner.demonstrations += 1
                number = self.app.learner.demonstrations
                at = self.app.learner.movement_count
                self.app.demonstration_sent(number, at)
            return {"ok": True, "message": f"sent demonstration {number}",
                    "demonstration": number, "movement": at}
        if isinstance(decision, ExecuteFirst):
            return {"ok": False, "message": "no simulator here"}
        assert isinstance(decision, PaceRequest)
        return {"ok": True, "message": decision.what}


class Watch(logging.Handler):
    """Every warning or error the server logs."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.records: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(self.format(record))


@pytest.fixture(scope="module")
def server():
    watch = Watch()
    logger = logging.getLogger("teacher.web")
    logger.addHandler(watch)
    api = PageApi()
    served = TeacherServer("127.0.0.1", 0, TOKEN, api)
    served.start()
    try:
        yield served, api, watch
    finally:
        served.stop()
        logger.removeHandler(watch)
        for test, counts in sorted(_by_test().items()):
            print(f"\n{test}: {sum(counts.values())} cases: "
                  + ", ".join(f"{what} {n}" for what, n in sorted(counts.items())))


@pytest.fixture
def quiet(capsys):
    """After the test: nothing printed on stderr by the server's threads (a traceback)."""
    yield
    printed = capsys.readouterr().err
    assert "Traceback" not in printed and not printed.strip(), printed


def _by_test() -> dict[str, collections.Counter]:
    out: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    for (test, what), n in TRIED.items():
        out[test][what] += n
    return out


# --- what is sent ----------------------------------------------------------------------------

EXTREMES = st.sampled_from([0, -1, 1, 2**31, -(2**63), 10**400, -(10**400), 1e308, -0.0,
                            0.5, float("nan"), float("inf"), float("-inf"), "", "1", "0.5",
                            "nan", "1e999", "\x00", "é" * 300, True, False, None])
SCALARS = (st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=40)
           | EXTREMES)
JSON = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
    st.sampled_from(["command", "key", "index", "x", ""]) | st.text(max_size=4), inner,
    max_size=3), max_leaves=6)
KEYS = st.sampled_from(["0123456789abcdef", "repeated-key-01", "short", "x" * 65, "bad key!"])
GOOD = {"index": st.integers(-2, 5), "x": st.floats(-1, 1), "y": st.floats(-1, 1),
        "offer": st.integers(0, 4), "key": st.uuids().map(lambda u: u.hex) | KEYS,
        "what": st.sampled_from(["pause", "resume", "step", "faster"]),
        "steps": st.integers(-1, 200_000),
        "text": st.lists(st.floats(-1.5, 1.5) | st.sampled_from([float("nan"), float("inf")]),
                         max_size=26).map(lambda v: " ".join(map(str, v)))}
COMMANDS = st.sampled_from(["teach", "offer", "confirm", "action", "pace", "close", "fly", ""])


# Mostly command-shaped objects whose fields are right (often enough to reach every
# decision), wrong or absurd; sometimes any JSON at all.
def often(good, bad=JSON, times: int = 3):
    """``good`` about ``times`` times as often as ``bad`` (one_of merges equal strategies, so
    the copies are made distinct)."""
    return st.one_of(*[good.map(lambda value: value) for _ in range(times)], bad)


NAMED_COMMANDS = st.fixed_dictionaries(
    {"command": COMMANDS, "key": often(st.uuids().map(lambda u: u.hex), KEYS | JSON, 4)},
    optional={name: often(good) for name, good in GOOD.items() if name != "key"})
COMMAND_BODIES = NAMED_COMMANDS | st.fixed_dictionaries(
    {"command": JSON}, optional={name: good | JSON for name, good in GOOD.items()}) | JSON


def nested(depth: int) -> bytes:
    return b"[" * depth + b"]" * depth


RAW_BODIES = (COMMAND_BODIES.map(lambda b: json.dumps(b).encode())
              | st.binary(max_size=300) | st.integers(1, 100_000).map(nested)
              | st.sampled_from([b"", b"{", b'{"command": "teach", "index": 1e999}',
                                 b'{"command": 1' + b"0" * 5000 + b"}",
                                 b'\xff\xfe{"command": "close"}', b"NaN", b"x" * 70_000]))
ROUTES = st.sampled_from(["/", "/index.html", *(f"/static/{n}" for n in sorted(STATIC_FILES)),
                          "/static/", "/static/../server.py", "/static/%2e%2e/app.py",
                          "/api/state", "/api/legend", "/api/command", "/lake.png",
                          "/cast.gif", "/nowhere", "//x", "*", "http://[::1/api/state",
                          "http://example.com/api/state", "/api/state/"])
QUERY_NAMES = st.sampled_from(["landings", "evaluations", "regions", "teaching", "log",
                               "token"]) | st.text(max_size=6)
QUERY_VALUES = (st.integers().map(str) | st.text(max_size=30) | st.just(TOKEN)
                | st.just("9" * 5000) | st.just("\uff11\uff12"))  # digits int() reads
QUERIES = (st.dictionaries(QUERY_NAMES, QUERY_VALUES, max_size=6).map(
    lambda q: "&".join(f"{quote(k)}={quote(v)}" for k, v in q.items()))
    | st.text(st.characters(min_codepoint=33, max_codepoint=255), max_size=60))
METHODS = st.sampled_from(["GET", "GET", "POST", "POST", "HEAD", "PUT", "DELETE", "OPTIONS",
                           "PATCH", "BREW", "get"])
HEADER_TEXT = st.text(st.characters(min_codepoint=32, max_codepoint=255), max_size=80)


@st.composite
def requests(draw, method=METHODS, route=ROUTES) -> tuple[str, bytes]:
    """(method, the raw request): a request line, headers right or wrong, a body."""
    name = draw(method)
    target = draw(route)
    query = draw(st.none() | QUERIES)
    if query is not None:
        target += "?" + query
    body = draw(RAW_BODIES) if name in ("POST", "PUT") or draw(st.integers(0, 9)) == 0 else b""
    port = "{port}"
    headers = {"Host": draw(st.just(f"127.0.0.1:{port}") | st.just(f"localhost:{port}")
                            | HEADER_TEXT)}
    if draw(st.integers(0, 4)):
        headers["X-Teacher-Token"] = draw(st.just(TOKEN) | HEADER_TEXT)
    if draw(st.integers(0, 4)):
        headers["X-Teacher"] = draw(st.just("1") | HEADER_TEXT)
    headers["Content-Length"] = draw(st.just(str(len(body))) | HEADER_TEXT
                                     | st.integers().map(str) | st.just(str(10**30)))
    if draw(st.booleans()):
        headers["Content-Type"] = draw(st.just("application/json") | HEADER_TEXT)
    for key, value in draw(st.dictionaries(
            st.text(st.characters(min_codepoint=33, max_codepoint=126,
                                  blacklist_characters=":"), min_size=1, max_size=12),
            HEADER_TEXT, max_size=3)).items():
        headers.setdefault(key, value)
    version = draw(st.sampled_from(["HTTP/1.1", "HTTP/1.1", "HTTP/1.0", "HTTP/2.0", "HTTP/x",
                                    ""]))
    line = f"{name} {target} {version}".rstrip()
    head = line + "\r\n" + "".join(f"{k}: {v}\r\n" for k, v in headers.items()) + "\r\n"
    return name, head.encode("utf-8", "surrogateescape") + body


# --- what comes back -----------------------------------------------------------------------

def exchange(port: int, raw: bytes) -> bytes:
    """Send raw bytes, say that is all (half-close), read until the server closes."""
    with socket.create_connection(("127.0.0.1", port), timeout=20) as s:
        with contextlib.suppress(ConnectionResetError, BrokenPipeError):
            s.sendall(raw.replace(b"{port}", str(port).encode()))
        with contextlib.suppress(OSError):
            s.shutdown(socket.SHUT_WR)
        chunks = []
        while True:
            try:
                chunk = s.recv(65536)
            except ConnectionResetError:
                break
            if not chunk:
                break
            chunks.append(chunk)
    return b"".join(chunks)


class _Bytes:
    def __init__(self, data: bytes) -> None:
        self.data = data

    def makefile(self, *_args, **_kwargs):
        return io.BytesIO(self.data)


def first_answer(data: bytes, method: str) -> tuple[int, str, bytes]:
    """The first HTTP answer in ``data``: (status, content type, body); it must be whole."""
    reply = http.client.HTTPResponse(_Bytes(data), method=method)
    reply.begin()
    assert reply.version in (10, 11), data[:200]
    body = reply.read()
    length = reply.getheader("Content-Length")
    assert length is not None and (method == "HEAD" or int(length) == len(body)), data[:300]
    return reply.status, reply.getheader("Content-Type") or "", body


def check_answer(data: bytes, method: str, test: str, server, request: bytes,
                 label: str = "") -> None:
    _, _, watch = server
    assert data, f"no answer to {request[:300]!r}"
    status, kind, body = first_answer(data, "HEAD" if method == "HEAD" else "GET")
    assert status != 500 and status < 600, (status, body, request[:300])
    if kind == "application/json":
        if method != "HEAD":
            value = json.loads(body)
            if status >= 400:
                assert value["ok"] is False and isinstance(value["message"], str)
    else:
        assert status == 200 and kind.split(";")[0] in (
            "text/html", "text/css", "text/javascript", "image/png", "image/gif"), (status, kind)
    assert not watch.records, watch.records
    outcome = "answered" if status < 300 else "refused"
    if kind == "application/json" and method != "HEAD" and status == 200:
        value = json.loads(body)
        if isinstance(value, dict) and value.get("ok") is False:
            outcome = "refused by the page's rules"
    TRIED[(test, f"{label}{status} {outcome}")] += 1


# --- the properties --------------------------------------------------------------------------

@FUZZ
@given(request=requests())
def test_any_request_to_any_route_gets_a_json_answer(server, quiet, request):
    method, raw = request
    check_answer(exchange(server[0].port, raw), method.upper(), "any request", server, raw)


@FUZZ
@given(body=often(NAMED_COMMANDS.map(lambda b: json.dumps(b).encode()), RAW_BODIES, 2),
       fresh=st.booleans())
def test_any_command_body_gets_an_answer_and_no_crash(server, quiet, body, fresh):
    """Well-addressed commands (the page's headers, the token) with any body at all."""
    served, api, _ = server
    if fresh:
        api.app = fresh_app()  # the rules (keys, one at a time) start again now and then
    raw = (f"POST /api/command HTTP/1.1\r\nHost: 127.0.0.1:{served.port}\r\n"
           f"X-Teacher-Token: {TOKEN}\r\nX-Teacher: 1\r\nContent-Type: application/json\r\n"
           f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n").encode() + body
    try:
        name = json.loads(body).get("command")
        label = f"{name}: " if name in ("teach", "offer", "confirm", "action", "pace",
                                        "close") else "other: "
    except (ValueError, AttributeError, RecursionError, TypeError):
        label = "not a command: "
    check_answer(exchange(served.port, raw), "POST", "any command body", server, raw, label)


@settings(FUZZ, max_examples=300)
@given(raw=st.binary(min_size=1, max_size=400) | st.text(max_size=200).map(
    lambda t: t.encode("utf-8")))
def test_any_bytes_at_all_get_an_answer_or_a_closed_connection(server, quiet, raw):
    """Not even a request: an answer in JSON, or, for a request line with nothing in it (a
    blank line, which HTTP says to ignore), the connection closed without one."""
    data = exchange(server[0].port, raw)
    words = raw.split(b"\n", 1)[0].decode("latin-1").split()
    if not data:
        assert not words, f"no answer to {raw[:200]!r}"
        TRIED[("any bytes", "closed (blank request line)")] += 1
        return
    method = words[0].upper() if words else "GET"
    check_answer(data, "HEAD" if method == "HEAD" else "GET", "any bytes", server, raw)
