"""Write the graph's reference page (docs/reference.md) from the code's own declarations.

One source for each fact, so the page cannot drift from the code: the nodes and who runs them
come from the graph description (description.py: NODES, graph()), the parameters from each
node module's PARAMS (a learner parameter's words from its LearnerConfig field docstring), the
topics, services and actions from each node module's INTERFACES (which the node creates its
endpoints from: sgim_ros/interfaces.py) and the
interfaces from the .msg/.srv/.action files and their comments. tests/docs/test_reference.py
fails while the page is not what this writes.

    python -m sgim_nodes.graph.reference --write docs/reference.md
    python -m sgim_nodes.graph.reference --check docs/reference.md   (exit 1 if out of date)
"""

from __future__ import annotations

import ast
import itertools
import sys
from collections.abc import Iterable, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from sgim_nodes.core.learner_registry import learner_kind, learner_names
from sgim_nodes.graph.description import (
    NODES,
    OPTION_PARAMETERS,
    NodeSpec,
    RunOptions,
    acts_teachers,
    graph,
    learner_defaults,
    parameters,
)
from sgim_ros.command_line import BriefParser
from sgim_ros.interfaces import CLIENT_KINDS, Endpoint

REPO = Path(__file__).resolve().parents[3]
# Where each top-level package's sources live (read from the tree, never from an install).
SOURCES = {"sgim_nodes": REPO / "sgim_nodes", "sim_bridge": REPO / "sim_bridge",
           "teacher": REPO / "teacher", "sgim_ros": REPO / "sgim_msgs"}
COMMAND = "python -m sgim_nodes.graph.reference --write docs/reference.md"
INTERFACES = REPO / "sgim_msgs"


def _cell(text: Any) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "`true`" if value else "`false`"
    return f'`"{value}"`' if isinstance(value, str) else f"`{value!r}`"


def _type(name: str) -> str:
    """A type name, linked to its section when it is one of ours."""
    package, folder, stem = name.split("/")
    return f"[`{name}`](#{folder}{stem.lower()})" if package == "sgim_msgs" else f"`{name}`"


def source(module: str) -> Path | None:
    """The source file of a project module in this tree (never an installed copy)."""
    top, *rest = module.split(".")
    if top not in SOURCES:
        return None
    base = SOURCES[top].joinpath(top, *rest)
    path = base / "__init__.py" if base.is_dir() else base.with_suffix(".py")
    return path if path.is_file() else None


def _summary(module: str) -> str:
    """The module docstring's first paragraph: what the node does."""
    path = source(module)
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) if path else ""
    doc = doc or ""
    return " ".join(doc.split("\n\n")[0].split())


@cache
def learner_docs() -> dict[str, str]:
    """LearnerConfig's field docstrings: the learner parameters' descriptions say "see" them."""
    path = source("sgim_nodes.core.config")
    tree = ast.parse(path.read_text(encoding="utf-8")) if path else ast.Module([], [])
    body = next(n for n in tree.body if isinstance(n, ast.ClassDef)
                and n.name == "LearnerConfig").body
    return {field.target.id: " ".join(doc.value.value.split())
            for field, doc in itertools.pairwise(body)
            if isinstance(field, ast.AnnAssign) and isinstance(field.target, ast.Name)
            and isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant)}


def _description(p: Any) -> str:
    if p.description == f"see LearnerConfig.{p.name} in core/config.py":
        return learner_docs().get(p.name, p.description) + " (LearnerConfig)"
    return p.description


def run_graph(learner: str, teacher: str, markers: bool) -> list[NodeSpec]:
    """The nodes of a run with the default parameters, as the launcher plans it: SGIM-ACTS's
    teachers are those its parameters() gives the run (the web page among them with
    --teacher web)."""
    options = RunOptions(learner, teacher=teacher, markers=markers)
    chooses = learner_kind(learner).chooses_teachers
    teachers = acts_teachers(parameters(options).shared) if chooses else None
    return graph(learner, teacher, markers, teachers)


def who_runs(spec: NodeSpec) -> str:
    """Which learners' graphs hold the node, with the teacher or markers it needs."""
    from sgim_nodes.graph.description import TEACHERS

    names = learner_names()

    def holds(nodes: list[NodeSpec]) -> bool:  # in any namespace (SGIM-ACTS's experts)
        return any((s.package, s.executable) == (spec.package, spec.executable) for s in nodes)

    runs = {(learner, teacher, markers) for learner in names for teacher in TEACHERS
            for markers in (True, False) if holds(run_graph(learner, teacher, markers))}
    learners = [name for name in names if any(r[0] == name for r in runs)]
    teachers = sorted({r[1] for r in runs}, key=TEACHERS.index)
    if not runs:
        return "no run (started by hand)"
    text = "every learner" if len(learners) == len(names) else ", ".join(learners)
    if len(teachers) < len(TEACHERS):
        text += f" (teacher {', '.join(teachers)})"
    if not any(not r[2] for r in runs):
        text += " (with markers on, the default)"
    return text


def _shared(nodes: Sequence[NodeSpec]) -> dict[Any, list[str]]:
    """Parameters declared alike (same default, description, check) by several nodes."""
    alike: dict[Any, list[str]] = {}
    for spec in nodes:
        for p in spec.params:
            alike.setdefault(p, []).append(spec.name)
    return {p: names for p, names in alike.items() if len(names) > 1}


def _param_table(params: Iterable[Any], declared_by: dict[Any, list[str]] | None = None
                 ) -> list[str]:
    run_values = learner_defaults()
    by = " declared by |" if declared_by else ""
    lines = [f"| name | default | range | read-only | in a run |{by} description |",
             "|---|---|---|---|---|" + ("---|" if declared_by else "") + "---|"]
    for p in params:
        run = ""
        if p.name in OPTION_PARAMETERS:
            run = f"set by {OPTION_PARAMETERS[p.name]}"
        elif p.name in run_values and run_values[p.name] != p.default:
            run = f"{_value(run_values[p.name])} (learner.yaml)"
        nodes = f" {', '.join(declared_by[p])} |" if declared_by else ""
        lines.append(f"| `{p.name}` | {_value(p.default)} | {_cell(p.rule)} | "
                     f"{'yes' if p.read_only else 'no'} | {_cell(run)} |{nodes} "
                     f"{_cell(_description(p))} |")
    return lines


def _config_files(name: str) -> list[str]:
    """The packaged parameter files with a section for this node (standalone use)."""
    import yaml

    return [str(path.relative_to(REPO)) for path in sorted(REPO.glob("*/config/*.yaml"))
            if name in (yaml.safe_load(path.read_text(encoding="utf-8")) or {})]


def _when(e: Endpoint) -> str:
    return _cell(e.when)


def node_section(spec: NodeSpec, shared: dict[Any, list[str]], found: list[Endpoint]
                 ) -> list[str]:
    files = ", ".join(f"[{f}](../{f})" for f in _config_files(spec.name))
    lines = [f"### {spec.name}", "", _summary(spec.params_module), "",
             f"- run as `ros2 run {spec.package} {spec.executable}`"
             + (", restarted when it dies" if spec.respawn else ""),
             f"- in the graph of: {who_runs(spec)}",
             f"- code: `{spec.params_module}`" + (f"; parameter file: {files}" if files else "")]
    if found:
        lines += ["", "| | name | type | QoS | when |", "|---|---|---|---|---|"]
        lines += [f"| {e.kind} | `{e.name}` | {_type(e.type)} | {e.qos} | {_when(e)} |"
                  for e in found]
    own = [p for p in spec.params if p not in shared]
    lines += ["", "Parameters:", "", *_param_table(own)] if own else []
    common = [p.name for p in spec.params if p in shared]
    if common:
        lines += ["", ("Also" if own else "Parameters:") + " the [shared parameters]"
                  "(#shared-parameters) " + ", ".join(f"`{n}`" for n in common) + "."]
    return lines


def graph_tables(found: dict[str, list[Endpoint]]) -> list[str]:
    """Who publishes and subscribes each topic, who serves and calls each service/action."""
    roles: dict[tuple[str, str], dict[str, list[Endpoint | str]]] = {}
    for node, ends in found.items():
        for e in ends:
            role = "client" if e.kind in CLIENT_KINDS else e.kind
            roles.setdefault((e.name, e.type), {}).setdefault(role, []).extend((node, e))
    lines = ["| topic | type | QoS | publishers | subscribers |", "|---|---|---|---|---|"]
    calls = ["| service / action | type | server | clients |", "|---|---|---|---|"]

    def who(pairs: list[Any], usual: set[str] = frozenset()) -> str:
        return ", ".join(f"{node}{f' ({e.qos})' if usual and e.qos not in usual else ''}"
                         + (" \\*" if e.conditional else "")
                         for node, e in zip(pairs[::2], pairs[1::2], strict=True))

    for (name, msg), by_role in sorted(roles.items()):
        if "publishes" in by_role or "subscribes" in by_role:
            pubs, subs = by_role.get("publishes", []), by_role.get("subscribes", [])
            usual = {e.qos for e in (pubs or subs)[1::2]}
            lines.append(f"| `{name}` | {_type(msg)} | {', '.join(sorted(usual))} | "
                         f"{who(pubs)} | {who(subs, usual)} |")
        else:
            servers = by_role.get("serves", []) + by_role.get("action server", [])
            calls.append(f"| `{name}` | {_type(msg)} | {who(servers)} | "
                         f"{who(by_role.get('client', []))} |")
    return [*lines, "", *calls]


def interface(path: Path) -> list[str]:
    """One .msg/.srv/.action file: its header comment, then its fields and their comments."""
    parts = {".msg": [], ".srv": ["Request", "Response"],
             ".action": ["Goal", "Result", "Feedback"]}[path.suffix]
    text = path.read_text(encoding="utf-8").splitlines()
    header = [line.lstrip("#").strip() for line in text[:next(
        (i for i, line in enumerate(text) if not line.startswith("#")), len(text))]]
    lines = [f"### {path.parent.name}/{path.stem}", "", " ".join(header), ""]
    lines += [f"**{parts[0]}**", ""] if parts else []
    rows: list[list[str]] = []

    def flush() -> None:
        if rows:
            lines.extend(["| field | type | value / default | comment |", "|---|---|---|---|",
                          *(f"| {' | '.join(row)} |" for row in rows), ""])
            rows.clear()

    for line in text[len(header):]:
        code, _, comment = (part.strip() for part in line.partition("#"))
        if line.strip() == "---":
            flush()
            parts.pop(0)
            lines += [f"**{parts[0]}**", ""]
        elif code:
            kind, name, *rest = code.replace("=", " = ").split(maxsplit=2)
            value = " ".join(rest).lstrip("= ")
            rows.append([f"`{name}`", f"`{kind}`", f"`{value}`" if value else "",
                         _cell(comment)])
        elif comment and line.startswith("#"):  # a note on the fields below
            flush()
            lines += [comment, ""]
        elif comment and rows:  # a comment's next line
            rows[-1][3] += " " + _cell(comment)
    flush()
    return lines


PYTHON_API = (("sgim_nodes.analysis", "load_runs", "sgim_nodes.analysis.frames"),)
"""(where a script imports it from, its name, the module whose docstring says the rest)."""


def python_api() -> list[str]:
    """The functions a script imports, with what their code says of them."""
    import importlib
    import inspect

    lines = ["## Python API", "",
             "What a script imports to read runs, with the documentation its code gives.", ""]
    for package, name, detail in PYTHON_API:
        function = getattr(importlib.import_module(package), name)
        lines += [f"### `{package}.{name}{inspect.signature(function)}`", "",
                  inspect.getdoc(function) or "", "",
                  inspect.getdoc(importlib.import_module(detail)) or "", ""]
    return lines


def render(nodes: Sequence[NodeSpec] | None = None) -> str:
    """The whole page, for `nodes` (every node of the graph by default)."""
    nodes = list(NODES.values()) if nodes is None else list(nodes)
    found = {spec.name: list(spec.interfaces) for spec in nodes}
    shared = _shared(nodes)
    lines = [f"*Generated by `{COMMAND}` from the code's declarations: do not edit by hand.*",
             "", "# Reference: nodes, topics, services, actions and parameters", "",
             "Generated from the graph description (`sgim_nodes/graph/description.py`: which "
             "nodes, for which learners), each node module's `PARAMS` and `INTERFACES` "
             "(`sgim_ros/interfaces.py`) and the interface files (`sgim_msgs/msg`, `srv`, "
             "`action`). Names "
             "are relative, so a run can live in a namespace; QoS profiles are those of "
             "`sgim_ros/qos.py`. \\* marks an endpoint that exists only under a condition, "
             "given in its node's section. What the topics mean together (movement indices, "
             "validation, the social modes): [node_graph.md](node_graph.md).", "",
             "## Graph", "", *graph_tables(found), "", "## Nodes", ""]
    for spec in nodes:
        lines += [*node_section(spec, shared, found[spec.name]), ""]
    lines += ["## Shared parameters", "",
              "Declared alike by several nodes; in a run each is set once for all of them "
              "(the `/**` section of `sgim_nodes/config/learner.yaml`).", "",
              *_param_table(sorted(shared, key=lambda p: p.name), shared), "",
              "## Interfaces", ""]
    for folder in ("msg", "srv", "action"):
        for path in sorted((INTERFACES / folder).glob(f"*.{folder}")):
            lines += interface(path)
    lines += ["", *python_api()]
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = BriefParser(description=__doc__.split("\n\n")[0])
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--write", metavar="FILE", type=Path, help="write the page")
    action.add_argument("--check", metavar="FILE", type=Path,
                        help="exit 1 if FILE is not what --write would write")
    args = parser.parse_args(argv)
    text = render()
    if args.write:
        args.write.write_text(text, encoding="utf-8")
        return 0
    current = args.check.read_text(encoding="utf-8") if args.check.is_file() else ""
    if current != text:
        print(f"{args.check} is out of date: run {COMMAND}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
