"""The web teacher's HTTP server without ROS: what needs its token, how many clients it takes
at once, and http.server's own refusals in JSON like every other answer."""

from __future__ import annotations

import http.client
import json
import socket
import threading
import urllib.error
import urllib.request

from teacher.web.server import RUN_OVER, Api, RunOver, TeacherServer

TOKEN = "a-token-of-sixteen+"


class FakeApi(Api):
    def state(self, query):
        return {"query": query}

    def command(self, body):
        return {"ok": True, "echo": body}

    def legend(self):
        return {}

    def image(self, name):
        return None


def _request(url, headers=None):
    request = urllib.request.Request(url, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, reply.headers["Content-Type"], reply.read()
    except urllib.error.HTTPError as error:
        return error.code, error.headers["Content-Type"], error.read()


def test_the_pages_own_files_need_no_token_and_everything_else_does():
    """With a token, index.html loads /static/teacher.css and teacher.js by their plain
    address: they must come without it (they were refused, the page unstyled and dead); what
    says something of the run still needs it."""
    server = TeacherServer("127.0.0.1", 0, TOKEN, FakeApi())
    server.start()
    try:
        base = f"http://127.0.0.1:{server.port}"
        for path, kind in (("/", "text/html"), ("/static/teacher.css", "text/css"),
                           ("/static/teacher.js", "text/javascript")):
            status, content_type, _ = _request(base + path)
            assert status == 200 and content_type.startswith(kind), path
        for path in ("/api/state", "/api/legend", "/lake.png", "/cast.gif"):
            status, _, body = _request(base + path)
            assert status == 401 and json.loads(body)["ok"] is False, path
        assert _request(f"{base}/api/state?token={TOKEN.replace('+', '%2B')}")[0] == 200
        assert _request(f"{base}/static/teacher.js", headers={"Host": "evil.example"})[0] == 403
    finally:
        server.stop()


def test_a_refused_token_says_what_is_wrong_and_which_address_to_open():
    """The page shows this message: it said only '401' (the server's words reached curl)."""
    server = TeacherServer("127.0.0.1", 0, TOKEN, FakeApi())
    server.start()
    try:
        base = f"http://127.0.0.1:{server.port}/api/state"
        for url, what in ((base, "no access token"), (f"{base}?token=wrong", "a wrong access "
                                                       "token")):
            status, _, body = _request(url)
            message = json.loads(body)["message"]
            assert status == 401 and message.startswith(f"{what}: open this page at the "
                                                        "address the run printed after "
                                                        "'teach at', with its ?token=")
    finally:
        server.stop()


class GoneApi(FakeApi):
    """An owner whose ROS side is gone: every call into it fails as rclpy's would."""

    def state(self, query):
        raise RunOver(RUN_OVER)

    def command(self, body):
        raise RunOver(RUN_OVER)


def test_once_the_run_is_gone_every_answer_about_it_is_a_one_line_503():
    """After the page's linger, calls into a shut-down ROS context were HTTP 500s."""
    for api, over in ((GoneApi(), ""), (FakeApi(), RUN_OVER)):
        server = TeacherServer("127.0.0.1", 0, TOKEN, api)
        server.over = over
        server.start()
        try:
            base, auth = f"http://127.0.0.1:{server.port}", {"X-Teacher-Token": TOKEN}
            connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
            connection.request("POST", "/api/command", body=b'{"command": "none"}',
                               headers={**auth, "X-Teacher": "1",
                                        "Content-Type": "application/json"})
            reply = connection.getresponse()
            answers = [(reply.status, reply.read())]
            connection.close()
            paths = ("/api/state", "/lake.png") if over else ("/api/state",)
            answers += [_request(base + path, auth)[::2] for path in paths]
            for status, body in answers:
                assert status == 503 and json.loads(body) == {"ok": False,
                                                              "message": RUN_OVER}
                assert b"\n" not in body and RUN_OVER.startswith("the run is over")
            assert _request(base + "/")[0] == 200  # the page itself still loads, and says it
        finally:
            server.stop()


def _raw(port: int, data: bytes) -> tuple[int, str, dict]:
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(data)
        s.shutdown(socket.SHUT_WR)
        reply = http.client.HTTPResponse(s)
        reply.begin()
        return reply.status, reply.getheader("Content-Type"), json.loads(reply.read())


def test_http_servers_own_refusals_are_json_too():
    """A bad request line, an unknown method, too new a version: http.server answered with
    an HTML page (or, for a line it could not read, a bare body with no status line)."""
    server = TeacherServer("127.0.0.1", 0, TOKEN, FakeApi())
    server.start()
    try:
        for data, status in ((b"PUT /api/state HTTP/1.1\r\n\r\n", 501),
                             (b"GET / HTTP/2.0\r\n\r\n", 505),
                             (b"\x00\x01 nonsense\r\n\r\n", 400),
                             (b"POST /api/command\r\n\r\n", 400),
                             (b"GET /api/state HTTP/1.1\r\n" + b"X: y\r\n" * 200 + b"\r\n", 431),
                             (b"GET http://[::1/api/state HTTP/1.1\r\n\r\n", 400)):
            got, kind, body = _raw(server.port, data)
            assert (got, kind, body["ok"]) == (status, "application/json", False), data[:40]
            assert isinstance(body["message"], str)
    finally:
        server.stop()


def test_a_crowd_of_fifty_clients_at_once_is_all_answered():
    """The accept backlog holds 50 clients connecting at the same moment: none is reset or
    left waiting for a SYN retransmission (the default backlog of 5 lost some of 20)."""
    served = TeacherServer("127.0.0.1", 0, TOKEN, FakeApi())
    served.start()
    try:
        _crowd(served.port)
    finally:
        served.stop()


def _crowd(port: int) -> None:
    for _ in range(2):
        barrier = threading.Barrier(50)
        failures: list[str] = []
        statuses: list[int] = []

        def one(barrier=barrier, statuses=statuses, failures=failures) -> None:
            barrier.wait()
            try:
                c = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
                c.request("GET", "/api/state?landings=0", headers={"X-Teacher-Token": TOKEN})
                reply = c.getresponse()
                reply.read()
                statuses.append(reply.status)
                c.close()
            except OSError as error:  # reset, refused, timed out
                failures.append(repr(error))

        threads = [threading.Thread(target=one) for _ in range(50)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not failures, failures
        assert statuses == [200] * 50
