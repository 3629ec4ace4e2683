"""The web teacher's HTTP server: the standard library's, one static page and a JSON API.

Why http.server and polling: the page needs a few small answers a second, and a thread per
request costs nothing at that rate; no framework, no build step, nothing to install. The page
(static/) asks GET /api/state with the cursors of what it already drew, four times a second,
and sends commands with POST /api/command.

Safety, since a page on another site could otherwise talk to it from the teacher's browser:
- it listens on 127.0.0.1 unless told otherwise; another interface needs an access token
  (``serve`` refuses without one), given as ``?token=`` in the page's address and sent by the
  page as the ``X-Teacher-Token`` header;
- on loopback, every request's Host header must name this server (no DNS rebinding); on
  another interface the Host is whatever name the teacher's machine uses for this one, and
  the token (which a rebinding page cannot know) is what keeps strangers out;
- commands need the ``X-Teacher: 1`` header and a JSON body, which a cross-site form cannot
  send and a cross-site script cannot send without a CORS preflight this server never grants.

Routes: GET / (the page), /static/<file>, /api/state, /api/legend, /lake.png, /cast.gif;
POST /api/command.
"""

from __future__ import annotations

import contextlib
import hmac
import ipaddress
import json
import logging
import socket
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

STATIC = Path(__file__).resolve().parent / "static"
CONTENT_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
                 ".css": "text/css; charset=utf-8", ".png": "image/png", ".gif": "image/gif"}
MAX_BODY = 64 * 1024
MIN_TOKEN = 16
WILDCARDS = ("0.0.0.0", "::")  # listen on every interface

log = logging.getLogger(__name__)


class Refused(ValueError):
    """The server cannot start with these settings; the message says why."""


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

    def __init__(self, host: str, port: int, token: str, api: Api) -> None:
        if not is_loopback(host) and len(token) < MIN_TOKEN:
            raise Refused(f"serving on {host} (not this machine only) needs an access token of "
                          f"at least {MIN_TOKEN} characters (parameter 'token')")
        self.token, self.api = token, api
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


class Handler(BaseHTTPRequestHandler):
    server: TeacherServer
    protocol_version = "HTTP/1.1"
    server_version = "sgim-web-teacher"

    def log_message(self, format: str, *args: Any) -> None:
        log.debug(format, *args)

    # --- checks ---------------------------------------------------------------------------

    def _allowed(self) -> bool:
        host = (self.headers.get("Host") or "").lower()
        if self.server.check_host and host not in self.server.allowed_hosts:
            self._send_json({"ok": False, "message": f"unknown host {host!r}"},
                            HTTPStatus.FORBIDDEN)
            return False
        token = self.server.token
        if token:
            given = self.headers.get("X-Teacher-Token") or ""
            if not given:
                given = parse_qs(urlsplit(self.path).query).get("token", [""])[0]
            if not hmac.compare_digest(given.encode(), token.encode()):
                self._send_json({"ok": False, "message": "a valid access token is needed "
                                 "(open the address the node printed, with its ?token=)"},
                                HTTPStatus.UNAUTHORIZED)
                return False
        return True

    # --- answers ----------------------------------------------------------------------------

    def _send(self, status: int, body: bytes, content_type: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", content_type)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("Referrer-Policy", "no-referrer")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _send_json(self, value: Any, status: int = HTTPStatus.OK) -> None:
        self._send(status, json.dumps(value, separators=(",", ":"), allow_nan=False).encode(),
                   "application/json")

    def do_GET(self) -> None:
        if not self._allowed():
            return
        path = urlsplit(self.path).path
        try:
            if path in ("/", "/index.html"):
                self._static("index.html")
            elif path.startswith("/static/"):
                self._static(path[len("/static/"):])
            elif path == "/api/state":
                self._send_json(self.server.api.state(self._cursors()))
            elif path == "/api/legend":
                self._send_json(self.server.api.legend())
            elif path in ("/lake.png", "/cast.gif"):
                data = self.server.api.image(path[1:])
                if data is None:
                    self._send_json({"ok": False, "message": "nothing yet"}, HTTPStatus.NOT_FOUND)
                else:
                    self._send(HTTPStatus.OK, data, CONTENT_TYPES[Path(path).suffix])
            else:
                self._send_json({"ok": False, "message": f"no page {path}"},
                                HTTPStatus.NOT_FOUND)
        except (BrokenPipeError, ConnectionResetError):
            pass

    def do_POST(self) -> None:
        # Read the body first, whatever the answer: on a kept-alive connection, unread bytes
        # would be taken for the next request (a refused command broke the page's next one).
        try:
            length = int(self.headers.get("Content-Length") or 0)
        except ValueError:
            length = -1
        if not 0 < length <= MAX_BODY:
            self.close_connection = True
            self._send_json({"ok": False, "message": f"a command is 1 to {MAX_BODY} bytes"},
                            HTTPStatus.BAD_REQUEST)
            return
        raw = self.rfile.read(length)
        if not self._allowed():
            return
        if urlsplit(self.path).path != "/api/command":
            self._send_json({"ok": False, "message": "commands go to /api/command"},
                            HTTPStatus.NOT_FOUND)
            return
        if self.headers.get("X-Teacher") != "1":
            self._send_json({"ok": False, "message": "commands need the X-Teacher: 1 header"},
                            HTTPStatus.FORBIDDEN)
            return
        try:
            body = json.loads(raw)
        except (json.JSONDecodeError, UnicodeDecodeError) as error:
            self._send_json({"ok": False, "message": f"the command is not JSON: {error}"},
                            HTTPStatus.BAD_REQUEST)
            return
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            self._send_json(self.server.api.command(body))

    def _cursors(self) -> dict[str, int]:
        query = parse_qs(urlsplit(self.path).query)
        cursors = {}
        for name in ("landings", "evaluations", "regions", "teaching", "log"):
            try:
                cursors[name] = int(query.get(name, ["-1"])[0])
            except ValueError:
                cursors[name] = -1
        return cursors

    def _static(self, name: str) -> None:
        file = (STATIC / name).resolve()
        if STATIC not in file.parents or not file.is_file() or file.suffix not in CONTENT_TYPES:
            self._send_json({"ok": False, "message": f"no file {name}"}, HTTPStatus.NOT_FOUND)
            return
        self._send(HTTPStatus.OK, file.read_bytes(), CONTENT_TYPES[file.suffix])


def serve(host: str, port: int, token: str, api: Api) -> TeacherServer:
    """Start serving in a background thread; Refused when the settings are not allowed."""
    server = TeacherServer(host, port, token, api)
    server.start()
    return server

