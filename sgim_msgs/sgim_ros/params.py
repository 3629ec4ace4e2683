"""Declare a node's parameters as ROS expects, and refuse bad values early and on change.

A typo in a parameter file should stop the node at start-up with a message naming the
parameter, never surface an hour into a run. Each parameter is declared with its default, its
description, its range (in the descriptor, so `ros2 param describe` shows it) and a read-only
flag: a parameter that shapes the run (the learner, the seed, the physics) cannot change while
it runs; the few that may (timeouts) are checked again on every change.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

INT_MAX = 2**63 - 1
FLOAT_MAX = sys.float_info.max


class ParameterError(ValueError):
    """A parameter has a value of the wrong type or out of its range, or is unknown."""


@dataclass(frozen=True)
class Bounds:
    """A numeric range, as a check (call it) that ROS descriptors can also carry."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False  # exclusive: a descriptor cannot say so; the check still does

    def __call__(self, value: float) -> bool:
        if self.low is not None and (value < self.low or (self.low_open and value == self.low)):
            return False
        return self.high is None or value <= self.high

    def __str__(self) -> str:
        low = None if self.low is None else f"{'>' if self.low_open else '>='} {self.low:g}"
        if self.high is None:
            return low or "any number"
        if self.low is None:
            return f"<= {self.high:g}"
        return f"in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}]"


positive = Bounds(0, low_open=True)
non_negative = Bounds(0)


def at_least(low: float) -> Bounds:
    return Bounds(low)


def between(low: float, high: float) -> Bounds:
    return Bounds(low, high)


@dataclass(frozen=True)
class OneOf:
    """A choice among names."""

    choices: tuple[str, ...]

    def __call__(self, value: str) -> bool:
        return value in self.choices

    def __str__(self) -> str:
        return "one of " + ", ".join(self.choices)


def one_of(*choices: str) -> OneOf:
    return OneOf(tuple(choices))


@dataclass(frozen=True)
class Param:
    """One parameter: its name, default (which fixes its type), meaning and check.

    `read_only`: the value is fixed for the node's life (the default); a parameter that may
    change while the node runs is declared `read_only=False` and is checked again on change.
    """

    name: str
    default: Any
    description: str
    check: Callable[[Any], bool] | None = None
    requirement: str = ""  # the check in words; Bounds and OneOf say it themselves
    read_only: bool = True

    @property
    def rule(self) -> str:
        return self.requirement or (str(self.check) if isinstance(self.check, Bounds | OneOf)
                                    else "")

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
                f"parameter '{self.name}' = {value!r} is invalid: it must be {self.rule}"
            )
        return value

    def descriptor(self):
        """The ROS ParameterDescriptor: description, range, choices, read-only flag."""
        from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

        # dynamic_typing: rclpy would otherwise refuse `1` for a float with its own terse
        # exception; validate() converts it or names the parameter and the expected type.
        descriptor = ParameterDescriptor(
            description=f"{self.description} ({self.rule})" if self.rule else self.description,
            dynamic_typing=True, read_only=self.read_only)
        if isinstance(self.check, OneOf):
            descriptor.additional_constraints = str(self.check)
        elif isinstance(self.check, Bounds):
            if type(self.default) is int:
                descriptor.integer_range = [IntegerRange(
                    from_value=int(self.check.low if self.check.low is not None else -INT_MAX),
                    to_value=int(self.check.high if self.check.high is not None else INT_MAX),
                    step=0)]
            elif type(self.default) is float:
                descriptor.floating_point_range = [FloatingPointRange(
                    from_value=float(self.check.low if self.check.low is not None
                                     else -FLOAT_MAX),
                    to_value=float(self.check.high if self.check.high is not None
                                   else FLOAT_MAX),
                    step=0.0)]
        return descriptor


def declare(node, params: Sequence[Param]) -> dict[str, Any]:
    """Declare every parameter on the node and return their validated values by name.

    The returned dict stays current: a change accepted at run time (only parameters declared
    `read_only=False` can change) is written into it, so a node that reads its values from it
    uses the new value. A change that fails the parameter's check is refused with the reason.
    """
    from rclpy.exceptions import InvalidParameterValueException

    by_name = {p.name: p for p in params}
    values: dict[str, Any] = {}
    for p in params:
        override = node._parameter_overrides.get(p.name)  # checked first: our message
        if override is not None:
            p.validate(override.value)
        try:
            raw = node.declare_parameter(p.name, p.default, p.descriptor()).value
        except InvalidParameterValueException as error:  # a range our check did not see
            raise ParameterError(f"parameter '{p.name}': {error}") from None
        values[p.name] = p.validate(raw)

    def check_change(changes):
        from rcl_interfaces.msg import SetParametersResult

        for change in changes:
            p = by_name.get(change.name)
            if p is None:
                continue  # not ours (use_sim_time and the like)
            try:
                p.validate(change.value)
            except ParameterError as error:
                return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def apply_change(changes) -> None:
        for change in changes:
            if change.name in by_name:
                values[change.name] = by_name[change.name].validate(change.value)
                node.get_logger().info(f"parameter {change.name} set to {change.value!r}")

    node.add_on_set_parameters_callback(check_change)
    node.add_post_set_parameters_callback(apply_change)
    return values
