"""Reserve a ROS_DOMAIN_ID that no other run on this host is using.

Two graphs on one domain mix their topics, so every run and every test run takes its own.
A domain is held by binding a loopback TCP port derived from it for as long as the
reservation lives; the operating system frees it when the last process holding the socket
dies, so a crashed run never leaks a reservation, and a run whose nodes inherited the socket
keeps its domain until its last node is gone.

A run holds one more lock beside it, its run lock (hold_run_domain): one run per domain,
whether the launcher chose the domain or `--domain` named it. A domain named by `--domain`
may be one that its caller reserved and lends (a test session starting its runs), so the run
lock, not the pool's port, is what refuses a second run.
"""

from __future__ import annotations

import os
import random
import socket
from dataclasses import dataclass, field

# Above the DDS port range of domains 0-232 (7400 + 250 * id + offsets, at most about 65,500)
# would collide, so stay in the low ephemeral range, which Linux hands out from 32768 upwards
# only when asked for port 0 and the default range is exhausted.
PORT_BASE = 30000
FIRST_DOMAIN = 1
LAST_DOMAIN = 100  # Fast DDS accepts 0-232 on Linux; 1-100 leaves room for other tools


RUN_LOCK = "sgim-ros-run-in-domain-{}"
"""The name of a domain's run lock: a socket in Linux's abstract namespace, which no file
holds and which the kernel frees with the last process that inherited it."""


class DomainInUse(RuntimeError):
    """The domain asked for is held by another run on this host."""


@dataclass
class DomainReservation:
    """A reserved domain id; release() or process exit frees it."""

    domain_id: int
    _socket: socket.socket | None = field(repr=False)
    _run_lock: socket.socket | None = field(default=None, repr=False)

    @property
    def fds(self) -> tuple[int, ...]:
        """Every descriptor that holds the domain: a child process that inherits them holds
        it until it ends too."""
        return tuple(s.fileno() for s in (self._socket, self._run_lock) if s is not None)

    def release(self) -> None:
        for sock in (self._socket, self._run_lock):
            if sock is not None:
                sock.close()

    def __enter__(self) -> DomainReservation:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def reserve_domain(preferred: int | None = None) -> DomainReservation:
    """Reserve a free domain id, `preferred` first if given; RuntimeError when none is free."""
    candidates = list(range(FIRST_DOMAIN, LAST_DOMAIN + 1))
    random.Random(os.getpid()).shuffle(candidates)
    if preferred is not None:
        if not 0 <= preferred <= 232:
            raise ValueError(f"ROS_DOMAIN_ID must be in 0..232, got {preferred}")
        candidates.insert(0, preferred)
    for domain_id in candidates:
        sock = _bind_pool_port(domain_id)
        if sock is not None:
            return DomainReservation(domain_id, sock)
    raise RuntimeError(
        f"no free ROS domain in {FIRST_DOMAIN}..{LAST_DOMAIN}: too many runs on this host?"
    )


def _bind(family: socket.AddressFamily, address: str | tuple[str, int]) -> socket.socket | None:
    """A socket bound to ``address``, or None when another holds it."""
    sock = socket.socket(family, socket.SOCK_STREAM)
    try:
        sock.bind(address)
    except OSError:
        sock.close()
        return None
    return sock


def _bind_pool_port(domain_id: int) -> socket.socket | None:
    return _bind(socket.AF_INET, ("127.0.0.1", PORT_BASE + domain_id))


def _bind_run_lock(domain_id: int) -> socket.socket | None:
    return _bind(socket.AF_UNIX, "\0" + RUN_LOCK.format(domain_id))


def hold_run_domain(requested: int | None = None) -> DomainReservation:
    """The domain a run holds for as long as any of its processes lives: ``requested`` (the
    launcher's `--domain`), or a free one of the pool. DomainInUse when another run holds
    ``requested``, in one line that says what to do."""
    if requested is not None:
        if not 0 <= requested <= 232:
            raise ValueError(f"ROS_DOMAIN_ID must be in 0..232, got {requested}")
        run_lock = _bind_run_lock(requested)
        if run_lock is None:
            raise DomainInUse(f"ROS domain {requested} is held by another run on this host: "
                              "leave out --domain to get a free one")
        # Taken from the pool too when free, so that no launcher picks it meanwhile; when the
        # pool's port is held, the caller that reserved it lends it to this run.
        return DomainReservation(requested, _bind_pool_port(requested), run_lock)
    skipped: list[DomainReservation] = []  # held while the next is tried, then let go
    try:
        while True:
            pooled = reserve_domain()  # RuntimeError once the pool has no free domain
            run_lock = _bind_run_lock(pooled.domain_id)
            if run_lock is not None:
                pooled._run_lock = run_lock
                return pooled
            skipped.append(pooled)  # a run named it while its caller held the pool's port
    finally:
        for other in skipped:
            other.release()


def isolated_ros_environment(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """The environment of a process that must only talk to its own graph on this host.

    A graph kept on this host talks over Fast DDS's shared memory alone (its discovery too):
    measured against its default transports (UDP and shared memory), 600 SGIM-D movements
    through the graph took 30 % less wall time and 5-12 % less CPU (docs/notes/measurements.md,
    2026-12-04). A range other than LOCALHOST, or a FASTDDS_BUILTIN_TRANSPORTS of the user's,
    keeps its say."""
    env = dict(os.environ if base is None else base)
    env["ROS_DOMAIN_ID"] = str(domain_id)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated; it would override the range above
    if env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST" and \
            env.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp") == "rmw_fastrtps_cpp":
        env.setdefault("FASTDDS_BUILTIN_TRANSPORTS", "SHM")
    return env
