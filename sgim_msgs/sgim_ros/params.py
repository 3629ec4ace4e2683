"""Declare a node's parameters as ROS expects, and refuse bad values early and on change.

A typo in a parameter file should stop the node at start-up with a message naming the
parameter, never surface an hour into a run. Each parameter is declared with its default, its
description, its range (in the descriptor, so `ros2 param describe` shows it) and a read-only
flag: a parameter that shapes the run (the learner, the seed, the physics) cannot change while
it runs; the few that may (timeouts) are checked again on every change.

`Param.validate` is the one check of a value, whoever gives it: a node at start-up and on a
change, the launcher and a sweep before any node starts (graph/description.py). Beyond the
declared range or choices it refuses what no parameter can mean: a NaN or infinite float, an
integer ROS cannot carry (64 bits), a string with a NUL character, and, for a parameter that
names a file (`DataFile`), a path that is not an existing file of the right format.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sgim_ros.clip import value_text

INT_MAX = 2**63 - 1
FLOAT_MAX = sys.float_info.max
SEED_MAX = 2**32 - 1
"""The largest seed of a run. numpy takes any integer >= 0 (SeedSequence, PCG64), but the
graph carries the seed in RunStatus.seed, a uint32: 2**32 would be recorded as 0, and past 64
bits a parameter file holds a float (1e+20) that every node refuses. Every entry
(run_experiment --seed, a sweep's seeds, `learn --seed`, the nodes' `seed`) uses this one
range; core/random_streams.SEED_MAX is the same number for the parts that run without ROS."""


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
        low = (None if self.low is None
               else f"{'>' if self.low_open else '>='} {_number(self.low)}")
        if self.high is None:
            return low or "any number"
        if self.low is None:
            return f"<= {_number(self.high)}"
        return (f"in {'(' if self.low_open else '['}{_number(self.low)}, "
                f"{_number(self.high)}]")


def _number(x: float) -> str:
    """A bound as people write it: 4294967295, not 4.29497e+09."""
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e16 else f"{x:g}"


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


seed_range = Bounds(0, SEED_MAX)


def seed_problem(value: Any) -> str | None:
    """Why `value` is not a seed of a run, or None: for command lines that take one."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= SEED_MAX:
        return f"a seed is an integer in 0..{SEED_MAX} (2**32 - 1), got {value_text(value)}"
    return None


@dataclass(frozen=True)
class DataFile:
    """A parameter that names a file of the project's data: empty means the project's own
    copy; anything else is a path the user names, which must be an existing regular file
    whose content `content` accepts (it returns why not, or None). Checked before any node
    starts, so a wrong path is one line, not a node dying at its first movement."""

    what: str  # "a teaching set (.npz: actions (M, 24), outcomes (M, 2), spread (M,))"
    content: Callable[[Path], str | None] | None = None

    def problem(self, value: str) -> str | None:
        """Why the path cannot be used, or None (empty: the project's own copy)."""
        if not value:
            return None
        path = Path(value)
        try:
            if not path.exists():
                return "no such file"
            if not path.is_file():  # a folder, a device, a pipe (reading one could hang)
                return "not a regular file"
            if not os.access(path, os.R_OK):
                return "the file cannot be read"
        except (OSError, ValueError) as error:  # a name too long, an unreadable folder
            return f"the path cannot be used ({getattr(error, 'strerror', None) or error})"
        try:
            found = self.content(path) if self.content is not None else None
        except Exception as error:  # a format check that did not foresee this content
            found = f"unreadable ({type(error).__name__}: {value_text(str(error))})"
        return None if found is None else f"not {self.what}: {found}"

    def __call__(self, value: str) -> bool:
        return self.problem(value) is None

    def __str__(self) -> str:
        return f"empty (the project's own) or the path of {self.what}"


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
        return self.requirement or (str(self.check) if isinstance(self.check,
                                                                  Bounds | OneOf | DataFile)
                                    else "")

    def validate(self, value: Any) -> Any:
        """The value as the node uses it, or ParameterError naming the parameter (one line)."""
        expected = type(self.default)
        if expected is float and isinstance(value, int) and not isinstance(value, bool):
            with contextlib.suppress(OverflowError):  # too large: refused below, by its type
                value = float(value)  # YAML writes 1 for 1.0
        if not isinstance(value, expected) or (expected is int and isinstance(value, bool)):
            raise ParameterError(
                f"parameter '{self.name}' must be of type {expected.__name__}, "
                f"got {value_text(value)} ({type(value).__name__})"
            )
        problem = _universal_problem(value)
        if problem is None and isinstance(self.check, DataFile):
            problem = self.check.problem(value)
        elif problem is None and self.check is not None and not self.check(value):
            problem = f"it must be {self.rule}"
        if problem is not None:
            raise ParameterError(f"parameter '{self.name}' = {value_text(value)} is invalid: "
                                 f"{problem}")
        if isinstance(self.check, DataFile) and value:
            # Absolute: the launcher checks it where the user named it, and a node (or a
            # resume started from another folder) reads the same file.
            value = os.path.abspath(value)
        return value

    def descriptor(self):
        """The ROS ParameterDescriptor: description, range, choices, read-only flag."""
        from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

        # dynamic_typing: rclpy would otherwise refuse `1` for a float with its own terse
        # exception; validate() converts it or names the parameter and the expected type.
        descriptor = ParameterDescriptor(
            description=f"{self.description} ({self.rule})" if self.rule else self.description,
            dynamic_typing=True, read_only=self.read_only)
        if isinstance(self.check, OneOf | DataFile):
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


def _universal_problem(value: Any) -> str | None:
    """What no parameter may hold, whatever its declared range."""
    if isinstance(value, float) and not math.isfinite(value):
        return "it must be a finite number"
    if isinstance(value, int) and not -INT_MAX - 1 <= value <= INT_MAX:
        return "it must fit in 64 bits (a ROS integer parameter)"
    if isinstance(value, str) and "\0" in value:
        return "it must not hold a NUL character"
    return None


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
