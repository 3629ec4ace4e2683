"""Declare a node's parameters with defaults and descriptions, and refuse bad values early.

A typo in a parameter file should stop the node at start-up with a message naming the
parameter, never surface an hour into a run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node


class ParameterError(ValueError):
    """A parameter has a value of the wrong type or out of its range."""


@dataclass(frozen=True)
class Param:
    """One parameter: its name, default (which fixes its type), meaning and check."""

    name: str
    default: Any
    description: str
    check: Callable[[Any], bool] | None = None
    requirement: str = ""  # the check in words, for the error message

    def validate(self, value: Any) -> Any:
        expected = type(self.default)
        if expected is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)  # YAML writes 1 for 1.0
        if not isinstance(value, expected) or (expected is int and isinstance(value, bool)):
            raise ParameterError(
                f"parameter '{self.name}' must be of type {expected.__name__}, "
                f"got {value!r} ({type(value).__name__})"
            )
        if self.check is not None and not self.check(value):
            raise ParameterError(
                f"parameter '{self.name}' = {value!r} is invalid: it must be {self.requirement}"
            )
        return value


def declare(node: Node, params: Sequence[Param]) -> dict[str, Any]:
    """Declare every parameter on the node and return their validated values by name."""
    values = {}
    for p in params:
        # dynamic_typing: rclpy would otherwise refuse `1` for a float with its own terse
        # exception; Param.validate converts it or names the parameter and the expected type.
        descriptor = ParameterDescriptor(
            description=f"{p.description} ({p.requirement})" if p.requirement else p.description,
            dynamic_typing=True,
        )
        raw = node.declare_parameter(p.name, p.default, descriptor).value
        values[p.name] = p.validate(raw)
    return values


def positive(value: float) -> bool:
    return value > 0


def non_negative(value: float) -> bool:
    return value >= 0


def one_of(*choices: str) -> Callable[[str], bool]:
    return lambda value: value in choices
