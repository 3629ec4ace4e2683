"""The web teacher's HTTP server: the standard library's, one static page and a JSON API.

Why http.server and polling: the page needs a few small answers a second, and a thread per
request costs nothing at that rate; no framework, no build step, nothing to install. The page
(static/) asks GET /api/state with the cursors of what it already drew, four times a second,
and sends commands with POST /api/command.

Safety, since a page on another site could otherwise talk to it from the teacher's browser:
- it listens on 127.0.0.1 unless told otherwise; another interface needs an access token
  (``serve`` refuses without one), given as ``?token=`` in the page's address and sent by the
  page as the ``X-Teacher-Token`` header. The page's own files (/, /static/) are served
  without it: they hold no data, and a browser fetches a stylesheet and a script by their
  plain address, so requiring it there left the page unstyled and dead; every answer that
  says something of the run (/api/, /lake.png, /cast.gif) needs it;
- on loopback, every request's Host header must name this server (no DNS rebinding); on
  another interface the Host is whatever name the teacher's machine uses for this one, and
  the token (which a rebinding page cannot know) is what keeps strangers out;
- commands need the ``X-Teacher: 1`` header and a JSON body, which a cross-site form cannot
  send and a cross-site script cannot send without a CORS preflight this server never grants.

Once the run is over and the node's ROS side is gone (its context shut down, the server not
stopped yet), every answer about the run is 503 with one line: ``over`` holds it, or the owner
raises ``RunOver``; never a 500 from a call into a dead context.

Robustness: whatever arrives (any bytes, headers, query or JSON body) gets an answer with a
JSON body: a valid one, or {"ok": false, "message": ...} with a 4xx status, http.server's own
refusals included (tests/teacher/test_web_server.py and test_web_fuzz.py try it). The listen
backlog holds a crowd of clients connecting at once (REQUEST_QUEUE), and a client that stops
sending is dropped after CLIENT_TIMEOUT seconds instead of holding its thread.

Routes: GET / (the page), /static/<file>, /api/state, /api/legend, /lake.png, /cast.gif;
POST /api/command. HEAD as GET.
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import logging
import socket
import sys
import threading
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

from sgim_ros.clip import clipped as cut

STATIC = Path(__file__).resolve().parent / "static"
STATIC_FILES = frozenset(p.name for p in STATIC.iterdir() if p.is_file())  # all it serves
CONTENT_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
                 ".css": "text/css; charset=utf-8", ".png": "image/png", ".gif": "image/gif"}
MAX_BODY = 64 * 1024
MIN_TOKEN = 16
WILDCARDS = ("0.0.0.0", "::")  # listen on every interface
REQUEST_QUEUE = 128  # the listen backlog: 5 (the default) reset a crowd of 20 clients
CLIENT_TIMEOUT = 30.0  # seconds a connection may stay silent
MESSAGE_LIMIT = 300  # characters of a refusal's message (it may quote what was sent)

log = logging.getLogger(__name__)


RUN_OVER = "the run is over: the web teacher no longer follows it"


class Refused(ValueError):
    """The server cannot start with these settings; the message says why."""


class RunOver(RuntimeError):
    """Raised by the owner (Api) once its run is gone: the request is answered 503."""


class Api:
    """What the server asks of its owner (the node); each call may come from any thread."""

    def state(self, query: dict[str, int]) -> dict[str, Any]:
        raise NotImplementedError

    def command(self, body: Any) -> dict[str, Any]:
        raise NotImplementedError

    def legend(self) -> dict[str, Any]:
        raise NotImplementedError

    def image(self, name: str) -> bytes | None:
        """The bytes of lake.png or cast.gif, or None when there is none (yet)."""
        raise NotImplementedError


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class TeacherServer(ThreadingHTTPServer):
    daemon_threads = True  # a page left open must not keep the node from ending
    allow_reuse_address = True
    request_queue_size = REQUEST_QUEUE

    def __init__(self, host: str, port: int, token: str, api: Api) -> None:
        if not is_loopback(host) and len(token) < MIN_TOKEN:
            raise Refused(f"serving on {host} (not this machine only) needs an access token of "
                          f"at least {MIN_TOKEN} characters (parameter 'token')")
        self.token, self.api = token, api
        self.over = ""  # set once the run is gone: every answer about it is a 503 saying this
        try:
            super().__init__((host, port), Handler)
        except OSError as error:
            raise Refused(f"cannot listen on {host}:{port}: {error.strerror or error}") from None
        self.host = host
        self.port = self.server_address[1]
        self.check_host = is_loopback(host)
        names = {f"{host}:{self.port}", f"127.0.0.1:{self.port}", f"localhost:{self.port}",
                 f"[::1]:{self.port}"}
        self.allowed_hosts = {n.lower() for n in names}
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address; on every interface (0.0.0.0, ::), by this machine's name."""
        host = socket.gethostname() if self.host in WILDCARDS else self.host
        host = f"[{host}]" if ":" in host else host
        address = f"http://{host}:{self.port}/"
        return f"{address}?token={self.token}" if self.token else address

    def start(self) -> None:
        self._thread = threading.Thread(target=self.serve_forever, name="web-teacher-http",
                                        kwargs={"poll_interval": 0.2}, daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self.shutdown()
        self.server_close()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A connection that failed outside a request's handling (the client went away):
        one line, not socketserver's traceback on stderr."""
        error = sys.exc_info()[1]
        if isinstance(error, OSError):
            log.debug("connection from %s ended: %r", client_address, error)
        else:
            log.error("connection from %s failed: %r", client_address, error)


def clipped(text: str, limit: int = MESSAGE_LIMIT) -> str:
    return cut(text, limit)


class Handler(BaseHTTPRequestHandler):
    server: TeacherServer
    protocol_version = "HTTP/1.1"
    # A request line too broken to name its version is answered as HTTP/1.0 (a status line
    # and headers), never as HTTP/0.9's bare body, which no client can tell from garbage.
    default_request_version = "HTTP/1.0"
    server_version = "sgim-web-teacher"
    timeout = CLIENT_TIMEOUT

    def log_message(self, format: str, *args: Any) -> None:
        log.debug(format, *args)

    def send_error(self, code: int, message: str | None = None,
                   explain: str | None = None) -> None:
        """http.server's own refusals (a bad request line, too long a header, an unknown
        method) in JSON like every other answer, not its HTML page."""
        if self.request_version == "HTTP/0.9":
            self.request_version = "HTTP/1.0"
        self.close_connection = True
        short = self.responses.get(code, ("error", ""))[0]
        self.log_error("code %d, message %s", code, message or short)
        self._send_json({"ok": False, "message": clipped(message or short)}, code,
                        close=True)

    # --- checks ---------------------------------------------------------------------------

    def _target(self) -> tuple[str, dict[str, list[str]]] | None:
        """The request's path and query; None (answered) when they cannot be read."""
        try:
            parts = urlsplit(self.path)
            return parts.path, parse_qs(parts.query)
        except ValueError as error:
            self._send_json({"ok": False, "message": clipped(f"unreadable address: {error}")},
                            HTTPStatus.BAD_REQUEST)
            return None

    def _allowed(self, query: dict[str, list[str]], needs_token: bool = True) -> bool:
        host = (self.headers.get("Host") or "").lower()
        if self.server.check_host and host not in self.server.allowed_hosts:
            self._send_json({"ok": False, "message": clipped(f"unknown host {host!r}")},
                            HTTPStatus.FORBIDDEN)
            return False
        token = self.server.token
        if token and needs_token:
            given = self.headers.get("X-Teacher-Token") or ""
            if not given:
                given = query.get("token", [""])[0]
            if not hmac.compare_digest(given.encode(), token.encode()):
                what = "a wrong access token" if given else "no access token"
                self._send_json({"ok": False, "message": f"{what}: open this page at the "
                                 "address the run printed after 'teach at', with its "
                                 "?token=... (the run folder's web_teacher.url holds it)"},
                                HTTPStatus.UNAUTHORIZED)
                return False
        if needs_token and self.server.over:
            self._send_json({"ok": False, "message": self.server.over},
                            HTTPStatus.SERVICE_UNAVAILABLE)
            return False
        return True

    # --- answers ----------------------------------------------------------------------------

    def _send(self, status: int, body: bytes, content_type: str, close: bool = False) -> None:
        self.send_response(status)
        if close:
            self.send_header("Connection", "close")
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _send_json(self, value: Any, status: int = HTTPStatus.OK, close: bool = False) -> None:
        self._send(status, json.dumps(value, separators=(",", ":"), allow_nan=False).encode(),
                   "application/json", close)

    def _guarded(self, handle: Callable[[], None]) -> None:
        """Run one request's handling; a client gone is routine, anything else a bug that
        still gets an answer (and one line in the log, which the fuzz test forbids)."""
        try:
            handle()
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            self.close_connection = True
        except RunOver as error:
            with contextlib.suppress(OSError):
                self._send_json({"ok": False, "message": clipped(str(error) or RUN_OVER)},
                                HTTPStatus.SERVICE_UNAVAILABLE)
        except Exception as error:
            self.close_connection = True
            log.error("the web teacher failed on %s %s: %r", self.command,
                      clipped(self.path, 200), error)
            with contextlib.suppress(OSError):
                self._send_json({"ok": False, "message": "the web teacher failed on this "
                                 "request (its log says why)"},
                                HTTPStatus.INTERNAL_SERVER_ERROR, close=True)

    def do_GET(self) -> None:
        self._guarded(self._get)

    def do_HEAD(self) -> None:
        self._guarded(self._get)

    def do_POST(self) -> None:
        self._guarded(self._post)

    def _get(self) -> None:
        target = self._target()
        if target is None:
            return
        path, query = target
        static = "index.html" if path in ("/", "/index.html") else (
            path[len("/static/"):] if path.startswith("/static/") else None)
        if not self._allowed(query, needs_token=static is None):
            return
        if static is not None:
            self._static(static)
        elif path == "/api/state":
            self._send_json(self.server.api.state(self._cursors(query)))
        elif path == "/api/legend":
            self._send_json(self.server.api.legend())
        elif path in ("/lake.png", "/cast.gif"):
            data = self.server.api.image(path[1:])
            if data is None:
                self._send_json({"ok": False, "message": "nothing yet"}, HTTPStatus.NOT_FOUND)
            else:
                self._send(HTTPStatus.OK, data, CONTENT_TYPES[Path(path).suffix])
        else:
            self._send_json({"ok": False, "message": clipped(f"no page {path}")},
                            HTTPStatus.NOT_FOUND)

    def _post(self) -> None:
        # Read the body first, whatever the answer: on a kept-alive connection, unread bytes
        # would be taken for the next request (a refused command broke the page's next one).
        try:
            length = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            length = -1
        if not 0 < length <= MAX_BODY:
            self._send_json({"ok": False, "message": f"a command is 1 to {MAX_BODY} bytes "
                             "with its Content-Length"}, HTTPStatus.BAD_REQUEST, close=True)
            self.close_connection = True
            return
        raw = self.rfile.read(length)
        target = self._target()
        if target is None or not self._allowed(target[1]):
            return
        if target[0] != "/api/command":
            self._send_json({"ok": False, "message": "commands go to /api/command"},
                            HTTPStatus.NOT_FOUND)
            return
        if self.headers.get("X-Teacher") != "1":
            self._send_json({"ok": False, "message": "commands need the X-Teacher: 1 header"},
                            HTTPStatus.FORBIDDEN)
            return
        try:
            body = json.loads(raw)
        except (ValueError, RecursionError) as error:  # JSON, UTF-8, too long a number
            self._send_json({"ok": False, "message": clipped(f"the command is not JSON: "
                                                             f"{error}")},
                            HTTPStatus.BAD_REQUEST)
            return
        self._send_json(self.server.api.command(body))

    @staticmethod
    def _cursors(query: dict[str, list[str]]) -> dict[str, int]:
        cursors = {}
        for name in ("landings", "evaluations", "regions", "teaching", "log"):
            try:
                cursors[name] = int(query.get(name, ["-1"])[0])
            except ValueError:  # not a number, or one of more than 4300 digits
                cursors[name] = -1
        return cursors

    def _static(self, name: str) -> None:
        """One of the page's own files, by its exact name: no path is ever resolved."""
        if name not in STATIC_FILES or Path(name).suffix not in CONTENT_TYPES:
            self._send_json({"ok": False, "message": clipped(f"no file {name}")},
                            HTTPStatus.NOT_FOUND)
            return
        self._send(HTTPStatus.OK, (STATIC / name).read_bytes(), CONTENT_TYPES[Path(name).suffix])


def serve(host: str, port: int, token: str, api: Api) -> TeacherServer:
    """Start serving in a background thread; Refused when the settings are not allowed."""
    server = TeacherServer(host, port, token, api)
    server.start()
    return server

