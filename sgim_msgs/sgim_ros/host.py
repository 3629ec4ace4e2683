"""A process hosting one node of the graph, or several on one executor (composition).

Every node stays its own class, runnable alone (`ros2 run PACKAGE NODE`); its module declares
once, in ``ENTRY``, how it starts. A composed process (sgim_nodes/nodes/composed.py) hosts
several such entries, each with its own parameters and namespace, on one EventsExecutor: a
message between them then costs a fraction of one between processes (docs/node_graph.md,
"Processes").

The rules of a lone node hold for each member: a member that cannot start says why in one line
and the process exits with code 2 (the members built so far destroyed); Ctrl-C, external
shutdown and the launcher's death end every member cleanly (the recorder, ended last, closes
its bag). A member that ends by itself (``finished``) is removed and destroyed while the others
spin, and its end is told to the launcher on the process's ends pipe (sgim_ros/ends.py).
Without that pipe (`ros2 launch`, which sees processes only), a member that ends with a
non-zero code ends the whole process, so that its failure is seen. The process's exit code is
the first non-zero one of its members'.
"""

from __future__ import annotations

import os
import sys
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import rclpy
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.node import Node

from sgim_ros.command_line import check_command_line, read_parameter_file, ros_arguments
from sgim_ros.ends import Ends
from sgim_ros.entry import (
    LAUNCHER_FD,
    AsyncNode,
    Profile,
    end_now,
    follow_launcher,
    tear_down,
)
from sgim_ros.executors import make_executor, spin_slice
from sgim_ros.params import ParameterError

CRASH_CODE = 1


@dataclass(frozen=True)
class NodeEntry:
    """How a node starts: its class (called with rclpy's node options), the exceptions that
    mean "cannot start with this configuration", and the executor it spins on alone
    ("events", or "single" for one that must; a node that awaits, an AsyncNode, spins on
    "single" when alone, and on the shared EventsExecutor when composed)."""

    factory: Callable[..., Node]
    refusals: tuple[type[Exception], ...] = ()
    executor: str = "events"

    @property
    def label(self) -> str:
        return self.factory.__name__

    def main(self, args: list[str] | None = None) -> int:
        """The node's own process: its console script's main."""
        return run_nodes(self.label, [Member(self.label, self)], args)


@dataclass(frozen=True)
class Member:
    """One node of a process: `name` as its launcher knows it ("recorder", "centre/expert":
    the namespace is what comes before the last slash)."""

    name: str
    entry: NodeEntry

    @property
    def namespace(self) -> str:
        return self.name.rpartition("/")[0]


def run_nodes(process: str, members: Sequence[Member], args: list[str] | None = None,
              ends_fd: int | None = None) -> int:
    """Create `members` in order and spin them on one executor until all have ended."""
    argv = sys.argv if args is None else args
    lone = len(members) == 1
    label = members[0].entry.label if lone else process

    def say(member: Member | None, text: str) -> None:
        prefix = label if lone or member is None else f"{process}] [{member.name}"
        print(f"[{prefix}] {text}", file=sys.stderr, flush=True)

    try:
        for path in ros_arguments(argv)[1]:
            read_parameter_file(path)  # rcl reads a file holding a plain string as "nothing"
        rclpy.init(args=argv)
    except ParameterError as error:
        say(None, str(error))
        return 2
    except Exception as error:  # rcl's own parse errors (RCLError): one line, not a traceback
        say(None, str(error).split(", at /")[0])
        return 2
    if not follow_launcher():
        say(None, "its launcher is gone: not starting")
        rclpy.try_shutdown()
        return 1
    nodes: dict[Member, Node] = {}
    for member in members:
        options = {"namespace": member.namespace} if member.namespace else {}
        try:
            nodes[member] = member.entry.factory(**options)
            check_command_line(nodes[member], argv)
        except (ParameterError, ValueError, FileNotFoundError, *member.entry.refusals) as error:
            say(member, str(error))
            for node in reversed(nodes.values()):
                node.destroy_node()
            rclpy.try_shutdown()
            return 2
    kind = members[0].entry.executor if lone else "events"
    if lone and isinstance(nodes[members[0]], AsyncNode):
        kind = "single"  # alone, a node that awaits keeps the executor it was proven on
    spinner = make_executor(kind, nodes.values())
    ends = Ends(ends_fd)
    codes: dict[Member, int] = {}
    live = dict(nodes)
    profile = Profile(label)
    unheard_failure = False  # a member failed, and no ends pipe tells of it
    try:
        with profile:
            while rclpy.ok() and len(codes) < len(members) and not unheard_failure:
                spin_slice(spinner)
                for member, node in list(live.items()):
                    if not getattr(node, "finished", False) or member in codes:
                        continue
                    codes[member] = int(getattr(node, "exit_code", 0))
                    ends.write(member.name, codes[member])
                    if codes[member] and ends_fd is None and not lone:
                        say(None, f"{member.name} failed (exit {codes[member]}): the "
                                  "process ends, as nothing else would tell of it")
                        unheard_failure = True
                        break
                    if not lone:  # the others go on spinning; a lone node ends below
                        del live[member]
                        end_member(spinner, node, member, say)
                        say(None, f"{member.name} ended (exit {codes[member]}); "
                                  f"{len(live)} node(s) go on")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if lone:
            raise
        say(None, "crashed:\n" + traceback.format_exc().rstrip())
        codes.update({member: CRASH_CODE for member in live if member not in codes})
    finally:
        profile.write()
        tear_down(label, spinner, list(reversed(live.values())))
        for member, node in live.items():
            codes.setdefault(member, int(getattr(node, "exit_code", 0)))
            ends.write(member.name, codes[member])
    code = next((codes[m] for m in members if codes.get(m)), 0)
    if os.environ.get(LAUNCHER_FD):
        end_now(code)
    return code


def end_member(executor: Executor, node: Node, member: Member,
               say: Callable[[Member | None, str], None]) -> None:
    """Remove a member that ended by itself; its peers' spin must not fail for it."""
    for what, step in (("removal", lambda: executor.remove_node(node)),
                       ("destruction", node.destroy_node)):
        try:
            step()
        except Exception as error:
            say(member, f"{what} after its end: {type(error).__name__}: {error}")
