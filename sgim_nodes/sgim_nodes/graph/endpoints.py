"""The topics, services and actions each node creates, read from its code (not run).

A node's names live where it creates them: `create_publisher(Movement, "movements",
qos.RECORDS)` and the like, in the node module or in the project's helpers it calls
(serve_ready, JobServer, SimClient, PaceControl...). This reads those calls from the source
tree: each create_* with a literal name (or a name its caller passes literally) is an
endpoint, and the node module's `if` tests around it are its condition. A name computed at
run time (a loop) cannot be read: DYNAMIC says where each such name comes from, and any other
stops the scan (ComputedName) rather than leave the reference short of it.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

from sgim_nodes.core.learner_registry import SGIM_D
from sgim_nodes.graph.description import NodeSpec

REPO = Path(__file__).resolve().parents[3]
# Where each top-level package's sources live (read from the tree, never from an install).
SOURCES = {"sgim_nodes": REPO / "sgim_nodes", "sim_bridge": REPO / "sim_bridge",
           "teacher": REPO / "teacher", "sgim_ros": REPO / "sgim_msgs"}
ROS = ("rclpy", "sgim_ros", "sgim_msgs")  # a module that names none of them creates nothing
# The creating call -> (kind, index of the type argument, of the name, of the QoS or None).
CREATORS = {"create_publisher": ("publishes", 0, 1, 2),
            "create_subscription": ("subscribes", 0, 1, 3),
            "create_service": ("serves", 0, 1, None), "create_client": ("calls", 0, 1, None),
            "ActionServer": ("action server", 1, 2, None),
            "ActionClient": ("action client", 1, 2, None)}
KINDS = ("publishes", "subscribes", "serves", "calls", "action server", "action client")
CLIENT_KINDS = ("calls", "action client")


@dataclass(frozen=True)
class Endpoint:
    """One topic, service or action a node creates; `condition`: the code's test around it."""

    kind: str
    name: str
    type: str
    qos: str = ""
    condition: str = ""  # code
    note: str = ""  # words, where no code says it


class ComputedName(LookupError):
    """A create_* call whose name the scan cannot read, and that DYNAMIC does not cover."""


def source(module: str) -> Path | None:
    """The source file of a project module in this tree (never an installed copy)."""
    top, *rest = module.split(".")
    if top not in SOURCES:
        return None
    base = SOURCES[top].joinpath(top, *rest)
    path = base / "__init__.py" if base.is_dir() else base.with_suffix(".py")
    return path if path.is_file() else None


@cache
def _module(name: str) -> tuple[dict[str, ast.AST], dict[str, str]] | None:
    """A ROS-facing project module's top-level definitions and what its names import; None
    for any other (the core is ROS-free: it creates no endpoint, and is not read)."""
    path = source(name)
    text = path.read_text(encoding="utf-8") if path else ""
    if not any(word in text for word in ROS):  # not worth parsing
        return None
    tree = ast.parse(text)
    defs = {n.name: n for n in tree.body
            if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)}
    imports: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            imports.update({a.asname or a.name: f"{node.module}.{a.name}" for a in node.names})
        elif isinstance(node, ast.Import):
            imports.update({a.asname or a.name: a.name for a in node.names})
    return defs, imports


@dataclass(frozen=True)
class _Scope:
    module: str
    bound: tuple[tuple[str, ast.expr, _Scope], ...] = ()  # a callee's parameters: the caller's

    def binding(self, name: str) -> tuple[ast.expr, _Scope] | None:
        return next(((e, s) for n, e, s in self.bound if n == name), None)

    def dotted(self, expr: ast.expr) -> str | None:
        """What a name or attribute stands for (e.g. sgim_msgs.msg.Movement), or None."""
        if isinstance(expr, ast.Name):
            if (bound := self.binding(expr.id)) is not None:
                return bound[1].dotted(bound[0])
            defs, imports = _module(self.module) or ({}, {})
            if expr.id in defs:
                return f"{self.module}.{expr.id}"
            return imports.get(expr.id)
        if isinstance(expr, ast.Attribute) and (base := self.dotted(expr.value)):
            return f"{base}.{expr.attr}"
        return None

    def literal(self, expr: ast.expr) -> str | None:
        if isinstance(expr, ast.Constant) and isinstance(expr.value, str):
            return expr.value
        if isinstance(expr, ast.Name) and (bound := self.binding(expr.id)) is not None:
            return bound[1].literal(bound[0])
        return None


class _Scanner:
    """Collects the endpoints that a node module's code creates, helpers included."""

    def __init__(self) -> None:
        self.found: set[Endpoint] = set()
        self.dynamic: set[tuple[str, int]] = set()  # (module, line) of a computed name
        self._done: set[tuple[Any, ...]] = set()
        self.node_module = ""

    def scan(self, module: str) -> None:
        self.node_module = module  # the node's own tests are its conditions; helpers' are not
        defs, _ = _module(module) or ({}, {})
        for definition in defs.values():
            self._walk(definition, _Scope(module), ())

    def _walk(self, node: ast.AST, scope: _Scope, conds: tuple[str, ...]) -> None:
        if isinstance(node, ast.If | ast.IfExp) and scope.module == self.node_module:
            test = ast.unparse(node.test)
            self._walk(node.test, scope, conds)
            for branch, cond in ((node.body, test), (node.orelse, f"not ({test})")):
                for child in branch if isinstance(branch, list) else [branch]:
                    self._walk(child, scope, (*conds, cond))
            return
        children = list(ast.iter_child_nodes(node))
        if isinstance(node, ast.Call):
            self._call(node, scope, conds)
            children.remove(node.func)  # followed with its arguments, not again without
        elif isinstance(node, ast.Name | ast.Attribute) and isinstance(node.ctx, ast.Load):
            self._follow(scope.dotted(node), None, scope, conds)
        for child in children:
            self._walk(child, scope, conds)

    def _call(self, call: ast.Call, scope: _Scope, conds: tuple[str, ...]) -> None:
        func = call.func
        short = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
        if short in CREATORS:
            kind, at_type, at_name, at_qos = CREATORS[short]
            args = call.args
            if len(args) <= at_name:
                return
            name = scope.literal(args[at_name])
            if name is None:
                self.dynamic.add((scope.module, call.lineno))
                return
            msg = (scope.dotted(args[at_type]) or ast.unparse(args[at_type])).split(".")
            qos = ""
            if at_qos is not None and len(args) > at_qos:
                qos = (scope.dotted(args[at_qos]) or ast.unparse(args[at_qos])).split(".")[-1]
            self.found.add(Endpoint(kind, name, "/".join(msg[-3:]), qos, " and ".join(conds)))
        elif isinstance(func, ast.Name | ast.Attribute):
            self._follow(scope.dotted(func), call, scope, conds)

    def _follow(self, target: str | None, call: ast.Call | None, scope: _Scope,
                conds: tuple[str, ...]) -> None:
        """Walk a project definition that the code uses, with the call's arguments bound."""
        if not target or "." not in target:
            return
        module, name = target.rsplit(".", 1)
        definition = (_module(module) or ({}, {}))[0].get(name)
        key = (module, name, ast.unparse(call) if call else "", scope.module, conds)
        if definition is None or key in self._done:
            return
        self._done.add(key)  # a definition met again the same way gives nothing new
        init = definition
        if isinstance(definition, ast.ClassDef):
            init = next((n for n in definition.body if isinstance(n, ast.FunctionDef)
                         and n.name == "__init__"), None)
        bound: list[tuple[str, ast.expr, _Scope]] = []
        if call is not None and init is not None:
            params = [a.arg for a in (*init.args.posonlyargs, *init.args.args)]
            if isinstance(definition, ast.ClassDef):
                params = params[1:]
            bound += [(p, a, scope) for p, a in zip(params, call.args, strict=False)]
            bound += [(k.arg, k.value, scope) for k in call.keywords if k.arg]
        for part in (definition.body if isinstance(definition, ast.ClassDef)
                     else [definition]):
            inner = _Scope(module, tuple(bound) if part is init else ())
            self._walk(part, inner, conds)


def scan(module: str) -> tuple[set[Endpoint], set[tuple[str, int]]]:
    """The endpoints a node module creates (read from its code) and its computed names."""
    scanner = _Scanner()
    scanner.scan(module)
    merged: dict[Endpoint, list[str]] = {}  # met under several conditions: any of them
    for e in scanner.found:
        merged.setdefault(replace(e, condition=""), []).append(e.condition)
    return ({replace(e, condition="" if "" in conds else " or ".join(sorted(conds)))
             for e, conds in merged.items()}, scanner.dynamic)


def recorder_endpoints() -> set[Endpoint]:
    """The recorder subscribes in a loop: its topics are bag.types' table, its QoS
    bag/live_topics.topic_qos's rule (state topics latched, kept whole)."""
    from sgim_nodes.bag.types import RECORDED_TOPICS, STATE_TOPICS

    return {Endpoint("subscribes", topic, msgtype, "LATEST_STATE, keep-all"
                     if topic.rsplit("/", 1)[-1] in STATE_TOPICS else "RECORDS")
            for topic, msgtype in RECORDED_TOPICS.items()}


def arbiter_ready_endpoints() -> set[Endpoint]:
    """The arbiter asks a ready service in a loop: the names are graph_startup's table."""
    from sgim_nodes.nodes.graph_startup import arbiter_graph

    expected = arbiter_graph(SGIM_D, True, True, True, True, execute=None, reach=None,
                             register=None, imitate=None)
    return {Endpoint("calls", service, "sgim_msgs/srv/RecorderReady",
                     note=f"when the run has {who}")
            for service, who in expected.listeners} | {
        Endpoint("calls", "expert_ready", "sgim_msgs/srv/RecorderReady",
                 note="sgim-acts: in the namespace of each of its teachers (/NAME/expert_ready)"),
        Endpoint("calls", "web/expert_ready", "sgim_msgs/srv/RecorderReady",
                 note="sgim-acts with the web page among its teachers")}


# The modules whose create_* calls compute their names, and where those names come from.
DYNAMIC = {"sgim_nodes.nodes.recorder": recorder_endpoints,
           "sgim_nodes.nodes.graph_startup": arbiter_ready_endpoints}


def endpoints(spec: NodeSpec) -> list[Endpoint]:
    """Every topic, service and action of a node: its code's, and its computed ones'."""
    found, dynamic = scan(spec.params_module)
    for module, line in sorted(dynamic):
        if module not in DYNAMIC:
            raise ComputedName(f"{source(module)}:{line}: a create_* call of {spec.name} "
                               "computes its name: add where it comes from to "
                               "sgim_nodes.graph.endpoints.DYNAMIC")
        found |= DYNAMIC[module]()
    return sorted(found, key=lambda e: (KINDS.index(e.kind), e.name))
