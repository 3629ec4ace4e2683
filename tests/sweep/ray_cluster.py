"""A Ray cluster of several nodes on this machine, started with `ray start` as on real ones.

Each node is one `ray start --block` in a session of its own, so it is stopped (SIGTERM: Ray
stops the node's processes) or lost (SIGKILL to its whole process group, as when a machine
dies) by its own process ids, never by name: other people's Ray processes are left alone.
Every node has its own temporary folder and every port is chosen free, so the nodes of this
machine do not collide, and the object store is kept small for a loaded 2-core machine.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from sgim_nodes.graph.processes import group_members

OBJECT_STORE = 80 * 1024**2  # Ray's minimum is 75 MiB
STARTED = "This command will now block forever"


def free_ports(count: int) -> list[int]:
    sockets = []
    try:
        for _ in range(count):
            s = socket.socket()
            s.bind(("", 0))
            sockets.append(s)
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


@dataclass
class RayNode:
    name: str
    process: subprocess.Popen
    log: Path

    def wait_started(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if STARTED in self.log.read_text(errors="replace"):
                return
            if self.process.poll() is not None:
                break
            time.sleep(0.5)
        raise RuntimeError(f"ray node {self.name} did not start:\n{self.log.read_text()[-3000:]}")

    def members(self) -> list[int]:
        return group_members(self.process.pid)

    def kill(self) -> None:
        """Lose the node as a machine is lost: every process of it at once, SIGKILL."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(timeout=30)

    def stop(self, timeout: float = 60) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)  # ray start stops its node's processes
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=timeout)
        self.kill()  # whatever is left of its group
        deadline = time.monotonic() + 30
        while self.members() and time.monotonic() < deadline:
            time.sleep(0.2)


@dataclass
class LocalCluster:
    """Token authentication on, with a token of its own in the environment of the nodes and
    of whoever joins (`env`): nothing read from or written to ~/.ray."""

    root: Path
    nodes: list[RayNode] = field(default_factory=list)
    address: str = ""
    env: dict[str, str] = field(default_factory=lambda: dict(
        os.environ, RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="token",
        RAY_AUTH_TOKEN=secrets.token_hex(32)))

    def _start(self, name: str, args: list[str]) -> RayNode:
        ports = free_ports(7)
        args += ["--block", "--num-cpus", "1", "--object-store-memory", str(OBJECT_STORE),
                 "--disable-usage-stats", "--node-manager-port", str(ports[0]),
                 "--object-manager-port", str(ports[1]),
                 "--dashboard-agent-listen-port", str(ports[2]),
                 "--dashboard-agent-grpc-port", str(ports[3]),
                 "--runtime-env-agent-port", str(ports[4]),
                 "--metrics-export-port", str(ports[5])]
        log = self.root / f"{name}.log"
        with log.open("wb") as out:
            process = subprocess.Popen([sys.executable, "-m", "ray.scripts.scripts", "start",
                                        *args], stdout=out, stderr=subprocess.STDOUT, env=self.env,
                                       start_new_session=True)
        node = RayNode(name, process, log)
        self.nodes.append(node)
        return node

    def start(self, workers: int = 1, timeout: float = 180) -> None:
        gcs, dashboard = free_ports(2)
        head = self._start("head", ["--head", "--port", str(gcs), "--temp-dir",
                                    str(self.root / "head"), "--include-dashboard", "false",
                                    "--dashboard-port", str(dashboard)])
        head.wait_started(timeout)
        self.address = f"127.0.0.1:{gcs}"
        for i in range(workers):
            name = f"worker{i + 1}"
            self._start(name, ["--address", self.address, "--temp-dir",
                               str(self.root / name)]).wait_started(timeout)

    def stop(self) -> None:
        for node in reversed(self.nodes):
            node.stop()
