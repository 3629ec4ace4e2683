"""The subpackages of sgim_nodes are layers: a module imports only from its own subpackage and
from lower layers, and no chain of imports comes back to where it started. Lazy imports (inside
a function) and relative ones (``from .x import y``) count: they still make the two modules
depend on each other. The core (the lowest layer) imports no world, teacher or ROS package:
worlds reach it through its registry (core/worlds.py)."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import REPO

PACKAGE = REPO / "sgim_nodes" / "sgim_nodes"
LAYERS = {
    "core": 0,
    "provenance": 1, "view": 1, "bag": 1,
    "nodes": 2, "analysis": 2,
    "graph": 3,
    "sweep": 4,
    "experiments": 5,
}
"""A subpackage may import any subpackage of a lower number (the core: none)."""


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def absolute(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute name ``from ... import`` reads from ``module`` (a package's own
    ``__init__`` is its package; a level of 1 is the module's package, 2 its parent...)."""
    if node.level == 0:
        return node.module or ""
    package = module.split(".") if is_package else module.split(".")[:-1]
    base = package[:len(package) - (node.level - 1)]
    return ".".join([*base, *([node.module] if node.module else [])])


def all_imports() -> dict[str, set[str]]:
    """Module -> every absolute name it imports, anywhere in its text (a name imported from a
    module counts as the submodule it may be)."""
    found: dict[str, set[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        name, targets = module_name(path), set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom):
                source = absolute(name, path.stem == "__init__", node)
                targets |= {source, *(f"{source}.{a.name}" for a in node.names)}
            elif isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
        found[name] = targets
    return found


def imports() -> dict[str, set[str]]:
    """Module -> the sgim_nodes modules it imports, anywhere in its text."""
    found = all_imports()
    return {name: {t for t in targets if t in found and t != name}
            for name, targets in found.items()}


def layer(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in LAYERS) else None


def test_every_subpackage_has_a_layer():
    assert {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()} == set(LAYERS)


def test_no_module_imports_a_higher_or_sibling_layer():
    wrong = []
    for module, targets in imports().items():
        mine = layer(module)
        for target in targets:
            theirs = layer(target)
            if mine and theirs and theirs != mine and LAYERS[theirs] >= LAYERS[mine]:
                wrong.append(f"{module} imports {target}")
    assert not wrong, "\n".join(sorted(wrong))


def test_no_import_cycle():
    graph = imports()
    cycles, state = [], {}  # state: 1 on the current path, 2 done

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for target in sorted(graph[module]):
            if state.get(target) == 1:
                cycles.append(" -> ".join([*path[path.index(target):], target]))
            elif target not in state:
                visit(target, [*path, target])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    assert not cycles, "\n".join(cycles)


FOREIGN = ("sim_bridge", "teacher", "rclpy", "sgim_msgs", "sgim_ros")
"""Packages the core never imports: the world (it registers itself, core/worlds.py), the
teacher's nodes and ROS."""


def test_the_core_imports_no_world_teacher_or_ros():
    wrong = sorted(f"{module} imports {target}" for module, targets in all_imports().items()
                   if layer(module) == "core" for target in targets
                   if target.split(".")[0] in FOREIGN)
    assert not wrong, "\n".join(wrong)


def test_relative_and_lazy_imports_are_read():
    core = imports()
    assert "sgim_nodes.core.learner_registry" in core["sgim_nodes.core.runner"]  # relative
    assert "sgim_nodes.core.acts_runner" in core["sgim_nodes.core.runner"]  # in main()
    assert "sgim_nodes.core.portable" in core["sgim_nodes.core.competence"]  # from . import
