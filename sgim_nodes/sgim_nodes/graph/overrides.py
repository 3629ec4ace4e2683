"""A run's parameter overrides from the command line: `--param NAME=VALUE` and `--params-file`.

Each problem is one line naming the option and the value, never a traceback: a malformed
value (`--param 'goal_budget=[1,'`), a file that is not a ROS parameter file (a plain string,
a list, a section without ros__parameters), a section that names neither every node (`/**`)
nor one node. Names and values are then checked against the graph (description.check).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import yaml

from sgim_ros.command_line import flatten, read_parameter_file
from sgim_ros.params import ParameterError

EVERY_NODE = ("/**", "**")


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
        try:
            value = yaml.safe_load(text) if text.strip() else ""
        except yaml.YAMLError as error:
            problem = getattr(error, "problem", None) or str(error).splitlines()[0]
            raise ParameterError(f"--param {item!r}: {text!r} is not a valid value "
                                 f"({problem})") from None
        if isinstance(value, dict) or value is None:
            raise ParameterError(f"--param {item!r}: a parameter value is a number, a "
                                 f"string, a boolean or a list, not {text!r}")
        values[name], where[name] = value, f" (--param {item})"
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
            if section in EVERY_NODE:
                shared.update(values)
                where.update(dict.fromkeys(values, f" (in {path})"))
                continue
            node = section.removeprefix("/**/").lstrip("/")
            if not node or "/" in node or "*" in node:
                raise ParameterError(f"parameter file {path}: section {section!r}: a run's "
                                     "file has sections /** (every node) or a node's name")
            per_node.setdefault(node, {}).update(values)
            where[node] = f" (section {section} of {path})"
    return shared, per_node, where


def _flat(body: dict[str, Any]) -> dict[str, Any]:
    """Nested mappings as dotted names, as ROS reads them."""
    flat: dict[str, Any] = {}
    for name in flatten(body):
        value: Any = body
        for part in name.split("."):
            value = value[part]
        flat[name] = value
    return flat
