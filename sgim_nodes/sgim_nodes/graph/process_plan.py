"""Which nodes of a run share a process (composition), and how that process is started.

Every node is its own class and may run alone; nodes sharing one process and one
EventsExecutor pass a message for a fraction of what it costs between processes. Nodes that
act in turn share one (no parallelism is lost), the nodes that observe the run another, while
the simulator, the evaluator and the teachers, which compute beside them, keep processes of
their own so that both cores work. The grouping and its figures: docs/node_graph.md,
"Processes".
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from sgim_nodes.graph.description import NodeSpec
from sgim_ros.params import ParameterError

CHAIN = ("low_level_explorer", "goal_generator", "imitation", "social_interaction")
"""The nodes that act strictly in turn (the arbiter starts a job, the explorer asks the goal
generator for each goal, or the imitation node imitates): in one process nothing is lost to
parallelism, and the goal generator's answer no longer waits behind the observers' work."""
OBSERVERS = ("recorder", "markers", "interest_computer")
"""The nodes that listen to the run and publish what they make of it."""
DEFAULT_GROUPS: Mapping[str, tuple[str, ...]] = {"chain": CHAIN, "observers": OBSERVERS}
ALWAYS_ALONE = ("web_teacher",)
"""Nodes never composed: the web teacher serves HTTP from threads of its own (and the terminal
teacher, `interactive`, needs the terminal)."""


@dataclass(frozen=True)
class ProcessSpec:
    """One process of a run: its name (its log's) and its nodes, in order."""

    name: str
    members: tuple[NodeSpec, ...]

    @property
    def composed(self) -> bool:
        return len(self.members) > 1

    @property
    def respawn(self) -> bool:
        """Restarted when it dies only if every node in it may be (a composed process is
        restarted as a whole)."""
        return all(spec.respawn for spec in self.members)

    @property
    def interactive(self) -> bool:
        return any(spec.interactive for spec in self.members)

    def node_options(self) -> list[str]:
        """`composed`'s options naming its nodes, in order: --node NAME=MODULE each."""
        return [a for spec in self.members for a in ("--node", f"{spec.name}={spec.params_module}")]

    def log_name(self, restarts: int = 0) -> str:
        return f"{self.name}.restart{restarts}" if restarts else self.name


def parse_groups(items: Iterable[str]) -> dict[str, tuple[str, ...]]:
    """--compose NAME=a,b,... options -> groups; ParameterError saying what is wrong."""
    groups: dict[str, tuple[str, ...]] = {}
    for item in items:
        name, sep, listed = item.partition("=")
        nodes = tuple(n.strip() for n in listed.split(",") if n.strip())
        if not sep or not name.strip() or not nodes:
            raise ParameterError(f"--compose expects NAME=NODE,NODE,..., got {item!r}")
        if "/" in name or name.strip() != name:
            raise ParameterError(f"--compose {item!r}: a process name holds no slash or space")
        if name in groups:
            raise ParameterError(f"--compose: process {name!r} is given twice")
        groups[name] = nodes
    return groups


def process_plan(nodes: Sequence[NodeSpec], groups: Mapping[str, Sequence[str]] | None = None,
                 separate: bool = False, alone: Iterable[str] = ()) -> list[ProcessSpec]:
    """The processes of a run of `nodes`, in the order of their first node.

    A node runs alone when `separate`, when it is in no group, when it is interactive or in
    ALWAYS_ALONE, or when it is named in `alone` (a node given its own --prefix); a group
    left with fewer than two of the run's nodes runs them alone. Names of nodes this run does
    not have are ignored (the default groups name every learner's); a node in two groups, or
    a group named like a node, is refused."""
    groups = DEFAULT_GROUPS if groups is None else groups
    by_name = {spec.name: spec for spec in nodes}
    owner: dict[str, str] = {}
    for group, members in groups.items():
        if group in by_name:
            raise ParameterError(f"process {group!r} is named like a node: name it otherwise")
        for name in members:
            if name in owner:
                raise ParameterError(f"node {name!r} is in two processes: {owner[name]!r} and "
                                     f"{group!r}")
            owner[name] = group
    alone = set(alone)
    kept: dict[str, list[NodeSpec]] = {}
    if not separate:
        for spec in nodes:
            group = owner.get(spec.name)
            if (group is not None and spec.name not in alone and not spec.interactive
                    and spec.executable not in ALWAYS_ALONE):
                kept.setdefault(group, []).append(spec)
    kept = {group: specs for group, specs in kept.items() if len(specs) > 1}
    placed = {spec.name: group for group, specs in kept.items() for spec in specs}
    plan, started = [], set()
    for spec in nodes:
        group = placed.get(spec.name)
        if group is None:
            plan.append(ProcessSpec(spec.name, (spec,)))
        elif group not in started:
            started.add(group)
            plan.append(ProcessSpec(group, tuple(kept[group])))
    return plan


def unknown_in_groups(groups: Mapping[str, Sequence[str]], known: Iterable[str]) -> list[str]:
    """Names in `groups` that no node of the graph has (a typo in --compose)."""
    known = set(known)
    return sorted({name for members in groups.values() for name in members} - known)
