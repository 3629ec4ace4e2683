"""The learner fingerprint: a hash of everything that can change a run's movements.

Why: a figure is only worth what its runs are, and runs of another learner, world or library
must never be pooled or reused as if they were alike. The fingerprint holds, each as a field
of its own so that a difference can be named:

- ``code``: the learner's core (sgim_nodes/core/*.py) that every learner runs through;
- ``learner_code``: the core modules that only some runs go through (LEARNER_MODULES:
  SGIM-ACTS's strategies, teachers and loop, for its runs and for SGIM-D's with teachers
  taking turns), empty for the others, so that work on SGIM-ACTS does not make the pages of
  the others stale;
- ``world``: the fishing world's modules (sim_bridge: the cast, the lake, the scaling, the
  data loaders);
- ``graph_code``: for a run made through the graph, its nodes' code (GRAPH_PACKAGES: the
  learner's nodes, the teachers, the simulator's node and the shared ROS helpers), so that a
  node edited locally makes sweeps make their runs again; absent from a runner's run, whose
  fingerprint it leaves as it was;
- ``data``: the world's data files (map, benchmark goals, teaching set, floor), by content;
- ``parameters``: the run's resolved parameters that shape it (``parameters`` below);
- ``numpy``, ``scipy``, ``pybullet``, ``python``: the versions that compute it.

Source files count by their syntax tree without docstrings (nor the strings that document a
dataclass's fields), so a comment or a docstring does not make a page stale, while any change
of code does. Nor is the machine: core/portable.py
makes a seed give the same run on every x86-64 CPU (tests/golden_runs.py holds the proof), so
reports name the machine but a figure made on one checks on another.
"""

from __future__ import annotations

import ast
import hashlib
import json
import platform
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import Any

from sgim_nodes.core.learner_registry import SGIM_ACTS, kinds

ENVIRONMENT_FIELDS = ("code", "world", "data", "numpy", "scipy", "pybullet", "python")
FIELDS = (*ENVIRONMENT_FIELDS, "learner_code", "graph_code", "parameters")
OPTIONAL_FIELDS = frozenset({"graph_code"})
"""Fields that count in the value only when set, so that fingerprints recorded before they
existed (and a runner's, which has none) keep their values."""
LEARNER_MODULES = {k.name: k.own_modules for k in kinds(plugins=False) if k.own_modules}
"""Core modules only one learner imports, as its declaration says
(tests/provenance/test_fingerprint.py checks that a run of any other learner does not,
unless its teachers take turns): they count in the ``learner_code`` of those runs only
(module_groups)."""
LIBRARIES = ("numpy", "scipy", "pybullet")
WORLD_MODULES = ("bezier", "core_world", "data_files", "fishing_world", "lake", "rod_urdf",
                 "scaling")
"""The sim_bridge modules a cast runs through and the one that builds the runner's world with
its seeds (not its node, renderer or tools)."""
GRAPH_PACKAGES = ("sgim_nodes.nodes", "teacher", "sgim_ros", "sim_bridge")
"""The packages whose modules make the graph's nodes (sim_bridge's world modules aside: they
count in ``world``)."""

PER_RUN = frozenset({"seed", "output", "resume_from", "resume_segments", "storage",
                     "wait_for_recorder", "movement_listeners", "ros_domain_id", "host",
                     "port", "token", "address_file"})
"""Parameters that differ between runs of one experiment without changing what the learner
does: the seed (a run's identity, kept beside the fingerprint), where it writes, how its
graph is wired and served."""
OPERATIONAL = frozenset({"startup_timeout", "settle_time", "map_timeout", "execute_timeout",
                         "wait_for_evaluation", "render_casts"})
"""Read-only parameters that say how patient a node is or what it draws, not what the
learner does: a slow machine may need a longer startup_timeout for the very same runs."""
SILENT_NODES = frozenset({"recorder", "markers"})
"""Nodes that only record or draw: their parameters cannot change a movement."""
OWN_PARAMETERS = {"teachers": lambda value, learner: learner == SGIM_ACTS,
                  "teacher_turns": lambda value, learner: bool(value)}
"""Parameters that nodes of every learner declare but only some runs read: SGIM-ACTS's
teachers, and teachers taking turns when there are some. A run that does not read one leaves
it out, as it cannot change its movements."""


def _digest(parts: Iterable[bytes], length: int = 16) -> str:
    h = hashlib.sha256()
    for part in parts:
        h.update(hashlib.sha256(part).digest())
    return h.hexdigest()[:length]


def _is_text(statement: ast.stmt) -> bool:
    """A bare string statement: a docstring, or the text documenting a dataclass field."""
    return (isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant)
            and isinstance(statement.value.value, str))


def _without_docstrings(tree: ast.AST) -> ast.AST:
    """The tree without its bare string statements (they do nothing when the code runs)."""
    for node in ast.walk(tree):
        for name in ("body", "orelse", "finalbody"):
            body = getattr(node, name, None)
            if isinstance(body, list) and any(isinstance(s, ast.stmt) and _is_text(s)
                                               for s in body):
                setattr(node, name, [s for s in body if not _is_text(s)] or [ast.Pass()])
    return tree


def source_digest(files: Iterable[Path]) -> str:
    """The files' code, by name and syntax tree (comments and docstrings do not count)."""
    parts = []
    for file in sorted(files, key=lambda f: f.name):
        tree = _without_docstrings(ast.parse(file.read_text(encoding="utf-8")))
        parts.append(file.name.encode() + b"\0" + ast.dump(tree).encode())
    return _digest(parts)


def file_digest(path: Path) -> str:
    """sha256 of a file's bytes (the first 16 hex digits)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def core_files() -> list[Path]:
    from sgim_nodes import core

    return sorted(Path(core.__file__).parent.glob("*.py"))


def _own_modules() -> set[str]:
    return {name for names in LEARNER_MODULES.values() for name in names}


def shared_core_files() -> list[Path]:
    """The core modules every learner runs through (all but LEARNER_MODULES)."""
    return [f for f in core_files() if f.stem not in _own_modules()]


def module_groups(parameters: Mapping[str, Any]) -> tuple[str, ...]:
    """The groups of LEARNER_MODULES a run with these parameters goes through."""
    turns = _found(parameters, "teacher_turns")
    return (SGIM_ACTS,) if learner_of(parameters) == SGIM_ACTS or turns else ()


def _found(parameters: Mapping[str, Any], name: str) -> Any:
    """A parameter at the top (a runner's run) or of any node (a graph's), else None."""
    if parameters.get(name):
        return parameters[name]
    return next((v[name] for v in parameters.values() if isinstance(v, Mapping)
                 and v.get(name)), None)


@cache
def learner_code(groups: tuple[str, ...]) -> str:
    """The digest of the core modules of these groups ("" when none)."""
    names = {n for group in groups for n in LEARNER_MODULES[group]}
    return source_digest([f for f in core_files() if f.stem in names]) if names else ""


def world_files() -> list[Path]:
    import sim_bridge

    here = Path(sim_bridge.__file__).parent
    return [here / f"{name}.py" for name in WORLD_MODULES]


def graph_files() -> list[Path]:
    """The modules of GRAPH_PACKAGES (sim_bridge's world modules aside)."""
    import importlib

    found = []
    for name in GRAPH_PACKAGES:
        folder = Path(importlib.import_module(name).__file__).parent
        found += [f for f in folder.glob("*.py")
                  if not (name == "sim_bridge" and f.stem in WORLD_MODULES)]
    return sorted(found, key=lambda f: (f.parent.name, f.name))  # wherever it is installed


@cache
def graph_code() -> str:
    """The digest of the graph's node code (by package, file name and syntax tree)."""
    return _digest([f"{f.parent.name}/".encode() + source_digest([f]).encode()
                    for f in graph_files()])


def data_files() -> dict[str, Path]:
    """The world's data files by name."""
    from sim_bridge import data_files as files

    folder = files.data_dir()
    return {name: folder / name for name in (files.REACHABLE_MAP, files.BENCHMARK_GOALS,
                                             files.TEACHING_SET, files.BENCHMARK_FLOOR)}


def python_release(version: str) -> str:
    """Python's major and minor release ('3.11' of '3.11.7'): what a fingerprint records."""
    return ".".join(version.split(".")[:2])


def library_versions() -> dict[str, str]:
    """The versions that can change a run: the libraries' (pinned by requirements.txt), and
    Python's major and minor (a patch release changes no arithmetic, and machines differ in
    it: Debian 12 has 3.11.2)."""
    found = {"python": python_release(".".join(platform.python_version_tuple()))}
    for dist in LIBRARIES:
        try:
            found[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            found[dist] = "absent"
    return found


@cache
def environment() -> dict[str, str]:
    """The fields every run of this checkout shares (computed once per process)."""
    data = data_files()
    return {"code": source_digest(shared_core_files()), "world": source_digest(world_files()),
            "data": _digest(f"{name}:{file_digest(path)}".encode()
                            for name, path in sorted(data.items())),
            **library_versions()}


def canonical(value: Any) -> str:
    """One text per value, whatever the order of mappings (JSON, keys sorted)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)


@dataclass(frozen=True)
class Fingerprint:
    """The fields, and ``parameters``: what they were made from (to name a difference)."""

    fields: Mapping[str, str]
    parameters: Mapping[str, Any] = field(default_factory=dict, compare=False)

    @property
    def value(self) -> str:
        return _digest(f"{k}={self.fields.get(k, '')}".encode() for k in FIELDS
                       if k not in OPTIONAL_FIELDS or self.fields.get(k))

    def differences(self, other: Fingerprint) -> list[str]:
        """The fields that differ; for ``parameters``, the parameters that do, by name."""
        out = [k for k in FIELDS if k != "parameters"
               and self.fields.get(k, "") != other.fields.get(k, "")]
        if self.fields.get("parameters") != other.fields.get("parameters"):
            names = parameter_differences(self.parameters, other.parameters)
            out.append(f"parameters ({', '.join(names)})" if names else "parameters")
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"value": self.value, "fields": dict(self.fields),
                "parameters": dict(self.parameters)}

    @classmethod
    def from_dict(cls, data: Any) -> Fingerprint | None:
        """Read back to_dict's mapping (None when absent or malformed: an older run). A run
        recorded before fingerprints held Python's major and minor release only holds its
        patch release too; it reads as the release today's fingerprints record."""
        if not isinstance(data, Mapping) or not isinstance(data.get("fields"), Mapping):
            return None
        fields_ = {str(k): str(v) for k, v in data["fields"].items()}
        if "python" in fields_:
            fields_["python"] = python_release(fields_["python"])
        params = data.get("parameters")
        return cls(fields_, dict(params) if isinstance(params, Mapping) else {})

    def describe(self) -> str:
        """One line: the value and its fields."""
        shown = ", ".join(f"{k} {self.fields.get(k, '?')}" for k in FIELDS)
        return f"{self.value} ({shown})"


def parameter_differences(a: Mapping[str, Any], b: Mapping[str, Any]) -> list[str]:
    """The parameter names whose values differ between a and b, once each: a graph run's
    parameters are nested by node, and one value is read by several nodes; a node that only
    one side has is named "node X"."""
    out: list[str] = []
    for key in sorted(set(a) | set(b)):
        va, vb = a.get(key), b.get(key)
        if isinstance(va, Mapping) and isinstance(vb, Mapping):
            out += parameter_differences(va, vb)
        elif isinstance(va, Mapping) != isinstance(vb, Mapping):
            out.append(f"node {key}")
        elif canonical(va) != canonical(vb):
            out.append(str(key))
    return list(dict.fromkeys(sorted(out)))


def learner_of(parameters: Mapping[str, Any]) -> str | None:
    """The ``learner`` parameter: at the top (a runner's run) or of a node (a graph's)."""
    if isinstance(parameters.get("learner"), str):
        return parameters["learner"]
    found = {v["learner"] for v in parameters.values()
             if isinstance(v, Mapping) and isinstance(v.get("learner"), str)}
    if len(found) > 1:
        raise ValueError(f"the nodes name several learners: {sorted(found)}")
    return found.pop() if found else None


def fingerprint(parameters: Mapping[str, Any], graph: bool = False) -> Fingerprint:
    """The fingerprint of a run of this checkout with these shaping parameters; ``graph``:
    made through the graph, so its nodes' code counts too."""
    params = json.loads(canonical(parameters))
    fields = {**environment(), "learner_code": learner_code(module_groups(params)),
              "parameters": _digest([canonical(params).encode()])}
    if graph:
        fields["graph_code"] = graph_code()
    return Fingerprint(fields, params)


def graph_parameters(node_parameters: Mapping[str, Mapping[str, Any]],
                     read_only: Mapping[str, Iterable[str]]) -> dict[str, dict[str, Any]]:
    """The parameters of a graph run that shape its movements: of every node but the silent
    ones, those it declares read-only (the ones it may change while it runs are timeouts),
    less the per-run (PER_RUN) and operational (OPERATIONAL) ones and those of another learner
    (OWN_PARAMETERS). ``read_only``: node -> its read-only parameter names."""
    out = {}
    learner = learner_of(node_parameters)
    for node, values in node_parameters.items():
        if node in SILENT_NODES:
            continue
        unread = {name for name, read in OWN_PARAMETERS.items()
                  if name in values and not read(values[name], learner)}
        keep = set(read_only.get(node, ())) - PER_RUN - OPERATIONAL - unread
        out[node] = {k: v for k, v in values.items() if k in keep}
    return out


def runner_parameters(env: str, learner: str, config: Mapping[str, Any],
                      options: Mapping[str, Any]) -> dict[str, Any]:
    """The parameters of a single-process run (core/runner.py): world, learner, every
    LearnerConfig field and the runner's options (teacher, budget, evaluation)."""
    return {"maker": "runner", "env": env, "learner": learner, "config": dict(config),
            "options": dict(options)}
