"""A run's parameter overrides from the command line: `--param NAME=VALUE` and `--params-file`.

Each problem is one line naming the option and the value, never a traceback: a malformed
value (`--param 'goal_budget=[1,'`), a file that is not a ROS parameter file (a plain string,
a list, a section without ros__parameters, binary content, a key given twice), a section that
names neither every node (`/**`) nor one node. Files and values are read as the nodes read
them (sgim_ros.command_line); names and values are then checked against the graph
(description.check).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from sgim_ros.command_line import YamlProblem, flat_items, parse_yaml, read_parameter_file, shown
from sgim_ros.params import ParameterError

EVERY_NODE = ("/**", "**")
PARAMETER_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*")


def parse_assignments(items: Sequence[str]) -> tuple[dict[str, Any], dict[str, str]]:
    """NAME=VALUE items -> values (VALUE read as YAML, as ROS reads `-p`) and where each was
    given."""
    values: dict[str, Any] = {}
    where: dict[str, str] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ParameterError(f"--param expects NAME=VALUE, got {item!r}")
        if not is_parameter_name(name):
            raise ParameterError(f"--param {item!r}: {name!r} is not a parameter name "
                                 "(letters, digits and _, parts joined by .)")
        try:
            value = parse_yaml(text) if text.strip() else ""
        except YamlProblem as problem:
            raise ParameterError(f"--param {item!r}: {text!r} is not a valid value "
                                 f"({str(problem).removeprefix('not valid YAML: ')})") from None
        if isinstance(value, dict) or value is None:
            raise ParameterError(f"--param {item!r}: a parameter value is a number, a "
                                 f"string, a boolean or a list, not {text!r}")
        values[name], where[name] = value, f" (--param {shown(item)})"
    return values, where


def read_parameter_files(paths: Sequence[Path]) -> tuple[dict[str, Any],
                                                         dict[str, dict[str, Any]],
                                                         dict[str, str]]:
    """ROS parameter files -> shared values (`/**`), per-node values (a section named after
    a node: `name`, `/name` or `/**/name`) and where each was given. Later files win."""
    shared: dict[str, Any] = {}
    per_node: dict[str, dict[str, Any]] = {}
    where: dict[str, str] = {}
    for path in paths:
        for section, body in read_parameter_file(path).items():
            values = _flat(body)
            bad = next((name for name in values if not is_parameter_name(name)), None)
            if bad is not None:
                raise ParameterError(f"parameter file {shown(path)}: section {section!r}: "
                                     f"{bad!r} is not a parameter name (letters, digits and "
                                     "_, parts joined by .)")
            if section in EVERY_NODE:
                shared.update(values)
                where.update(dict.fromkeys(values, f" (in {shown(path)})"))
                continue
            node = section.removeprefix("/**/").lstrip("/")
            if not node or "/" in node or "*" in node:
                raise ParameterError(f"parameter file {shown(path)}: section {section!r}: a run's "
                                     "file has sections /** (every node) or a node's name")
            per_node.setdefault(node, {}).update(values)
            where[node] = f" (section {shown(section)} of {shown(path)})"
    return shared, per_node, where


def is_parameter_name(name: str) -> bool:
    """A name a node could declare: what else reaches the graph's check would only be
    refused there, with less to say (a newline in it would break its one line)."""
    return PARAMETER_NAME.fullmatch(name) is not None


def _flat(body: dict[str, Any]) -> dict[str, Any]:
    """Nested mappings as dotted names, as ROS reads them."""
    return dict(flat_items(body))
