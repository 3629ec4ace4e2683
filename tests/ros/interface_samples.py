"""Every interface of sgim_msgs, filled with distinct non-default values, for round-trip tests."""

from __future__ import annotations

import importlib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
MSG_DIR = REPO / "sgim_msgs" / "msg"


def message_names() -> list[str]:
    """Names of all message types, read from the package's .msg files so none is forgotten."""
    return sorted(p.stem for p in MSG_DIR.glob("*.msg"))


def message_class(name: str) -> type:
    return getattr(importlib.import_module("sgim_msgs.msg"), name)


def _value(type_name: str, seed: int):
    if type_name.startswith("sequence<"):
        inner = type_name[len("sequence<") : -1].split(",")[0]
        return [_value(inner, seed + k) for k in range(1, 3)]
    if type_name in ("double", "float"):
        return seed + 0.25
    if type_name == "boolean":
        return seed % 2 == 1
    if type_name == "string":
        return f"text-{seed}"
    if type_name.startswith(("int", "uint", "octet")):
        return seed % 100 + 1
    if "/" in type_name:  # a nested message such as builtin_interfaces/Time
        package, name = type_name.split("/")
        cls = getattr(importlib.import_module(f"{package}.msg"), name)
        return filled(cls, seed)
    raise TypeError(f"no sample value for field type {type_name}")


def filled(cls: type, seed: int = 1):
    """An instance of cls with every field set to a value that differs from its default."""
    msg = cls()
    for i, (field, type_name) in enumerate(cls.get_fields_and_field_types().items()):
        setattr(msg, field, _value(type_name, seed + 3 * i))
    return msg
