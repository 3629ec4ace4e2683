"""What every learner node shares: message <-> numpy conversions, the learner parameters, the
action server of movement-by-movement jobs. Only translation lives here; algorithms stay in
`core`.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import fields
from typing import Any

import numpy as np
from rclpy.action import CancelResponse, GoalResponse
from rclpy.node import Node

from sgim_msgs.msg import Region, RegionMap
from sgim_nodes.bag.record_checks import vector_problem
from sgim_nodes.core.config import RANGES, TIES, LearnerConfig, Range
from sgim_nodes.core.environment import PROCESS_CODES, PROCESS_LABELS  # noqa: F401 - for nodes
from sgim_nodes.core.learner_registry import OWN_NAMES, SGIM_ACTS, SGIM_D, is_learner
from sgim_nodes.core.region_snapshot import RegionSnapshot, RegionSummary
from sgim_nodes.core.scale import WorldScale, unit_box
from sgim_nodes.core.social_config import SocialConfig, declared, turn_names
from sgim_ros.entry import AsyncNode  # noqa: F401 - the nodes' base
from sgim_ros.params import (
    Bounds,
    OneOf,
    Param,
    ParameterError,
    at_least,
    declare,
    one_of,
    positive,
    seed_range,
)
from sim_bridge.scaling import OUTCOME_NOISE

ACTION_SIZE = 24  # the fishing world's; a parameter of every node that checks sizes
ACTS = SGIM_ACTS
OUTCOME_SIZE = 2
JOB_RESULT_SECONDS = 1
"""How long a job server keeps a finished job's result (rclpy's default is 900 s). Every job's
status stays in the action's status array for that long, and the array is republished, and
deserialised by the arbiter, at every job's change of state: with 900 s a 5000-movement run
carried thousands of finished jobs in each message, and the arbiter spent most of its CPU
reading them (measured with py-spy; the graph took 3.6 times the runner's time). A goal
attempt takes about 1.6 movements, so even 5 s kept 60 to 150 jobs in every array (the
arbiter's CPU per movement fell by a fifth from 5 s to 1 s, bench_graph_vs_runner.py). The
arbiter asks for a job's result as soon as the job is accepted, before the job can end; a
result asked too late would come back with an unknown status, which the arbiter refuses
loudly (never a movement count gone astray)."""


class JobServer:
    """A long job driven movement by movement, served as a ROS 2 action, one at a time.

    A second goal is refused while a job runs (the arbiter sends one at a time); a cancel is
    always accepted and the job honours it at its next movement boundary, then says so in its
    result (`cancelled`). A job that refuses its request aborts the goal itself.
    """

    def __init__(self, node: Node, endpoint: Any, job: Callable[[Any], Awaitable[Any]]
                 ) -> None:
        """`endpoint`: the node's declared action server (sgim_ros/interfaces.py)."""
        self.job = job
        self.node, self.name, self.action_type = node, endpoint.name, endpoint.interface()
        self.busy = False
        self._server = endpoint.create(
            node, self._execute,
            goal_callback=lambda _: GoalResponse.REJECT if self.busy else GoalResponse.ACCEPT,
            cancel_callback=lambda _: CancelResponse.ACCEPT, result_timeout=JOB_RESULT_SECONDS)

    async def _execute(self, handle) -> Any:
        from sgim_nodes.nodes.sim_client import SimulatorError

        self.busy = True
        try:
            result = await self.job(handle)
        except SimulatorError as error:  # the simulator is gone: the job cannot go on
            self.node.get_logger().error(f"{self.name} job aborted: {error}")
            handle.abort()
            return self.action_type.Result()
        finally:
            self.busy = False
        if handle.is_active:
            if result.cancelled:
                handle.canceled()
            else:
                handle.succeed()
        return result


def vec(values: Sequence[float]) -> np.ndarray:
    return np.asarray(values, dtype=float)


def floats(array: np.ndarray | Sequence[float] | None) -> list[float]:
    return [] if array is None else np.asarray(array, dtype=float).ravel().tolist()


def check_vector(values: Sequence[float], size: int, what: str, bound: float = 1.0) -> str:
    """Why a vector from a message is unusable, or '' when it is fine: the readers' check
    (bag/validation.py); actions, outcomes and goals all live in [-1, 1]."""
    problem = vector_problem(values, size, what, bound)
    return "" if problem is None else problem.detail


COMMON_PARAMS = (
    Param("learner", SGIM_D, "which learner the graph runs", is_learner,
          f"one of {', '.join(OWN_NAMES)}, or a learner another package declares "
          "(core/learner_registry.py)"),
    Param("seed", 0, "seed of the run; each node derives its own random stream from it",
          seed_range),
    Param("action_size", ACTION_SIZE, "numbers per action (the world's action size)",
          at_least(1)),
    Param("outcome_size", OUTCOME_SIZE, "numbers per outcome (the world's outcome size)",
          at_least(1)),
    Param("outcome_noise", OUTCOME_NOISE, "the world's outcome noise (the paper's measure, in "
          "outcome units): every learner distance is a multiple of it (core/scale.py)",
          positive),
    Param("resume_from", "", "run folder to resume: state is rebuilt from its recordings "
          "(see bag/resume.py); empty for a fresh run"),
    Param("resume_segments", 0, "how many of its recordings to read (0: all)", at_least(0)),
)

def ros_check(bound: Range) -> OneOf | Bounds:
    """A core range (core/config.Range) as a ROS parameter's check."""
    return one_of(*bound.choices) if bound.choices else Bounds(bound.low, bound.high,
                                                                bound.low_open)


LEARNER_BOUNDS = {name: ros_check(r) for name, r in RANGES.items()}
"""The range of each LearnerConfig field as a ROS parameter's check (core/config.RANGES)."""


def learner_requirement(name: str) -> str:
    """A learner parameter's range, then the rules that tie it to others (config.TIES), in
    words: what its descriptor and the reference page say. Only the range is the Param's
    check; LearnerConfig checks the values together."""
    ties = [tie.rule for tie in TIES if name in tie.fields]
    return "; ".join([str(LEARNER_BOUNDS[name]), *ties])


def learner_params() -> tuple[Param, ...]:
    """One read-only ROS parameter per LearnerConfig field, with the documented default and
    range; LearnerConfig itself checks the values together."""
    default = LearnerConfig()
    return tuple(
        Param(f.name, getattr(default, f.name), f"see LearnerConfig.{f.name} in core/config.py",
              LEARNER_BOUNDS.get(f.name), learner_requirement(f.name))
        for f in fields(LearnerConfig)
    )


def world_scale(values: dict[str, Any]) -> WorldScale:
    """The fishing world's outcome box [-1, 1]^outcome_size and its outcome noise."""
    return unit_box(values["outcome_size"], values["outcome_noise"])


def teacher_names(text: str) -> list[str]:
    """The teachers of a `teachers` parameter: comma-separated names, blanks ignored."""
    return [name.strip() for name in str(text).split(",") if name.strip()]


def _teachers_ok(text: str) -> bool:
    from sgim_nodes.core.strategies import TEACHER_NAME

    names = teacher_names(text)
    return len(set(names)) == len(names) and all(TEACHER_NAME.fullmatch(n) for n in names)


TEACHERS = Param("teachers", "centre,west,rough", "sgim-acts: the teachers it may ask, "
                 "comma-separated; each is an expert node in the namespace of its name (ros2 "
                 "run teacher expert --ros-args -r __ns:=/NAME)", _teachers_ok,
                 "distinct names, each a letter then letters, digits or '_'")


def social_params(*names: str) -> tuple[Param, ...]:
    """The ROS parameters of these run-level social settings, as core/social_config.py
    declares them once: the same name, default, meaning and bounds."""
    params = []
    for name in names:
        d = declared(name)
        params.append(Param(name, d["default"], f"{d['help']}; SocialConfig.{name} in "
                            "core/social_config.py", ros_check(d["range"])))
    return tuple(params)


def social_config(values: Mapping[str, Any]) -> SocialConfig:
    """The run-level settings among a node's parameter values, checked once, as the core
    checks them (core/social_config.py): ParameterError names what is wrong. A node's
    `teacher_turns` is its comma-separated names."""
    names = {f.name for f in fields(SocialConfig)}
    given = {k: v for k, v in values.items() if k in names}
    if isinstance(given.get("teacher_turns"), str):
        given["teacher_turns"] = turn_names(given["teacher_turns"])
    try:
        return SocialConfig(**given)
    except ValueError as error:
        raise ParameterError(f"parameter {error}") from error


def learner_node_params(*extra: Param) -> tuple[Param, ...]:
    """Every parameter of a learner node: the common ones, the learner's, then its own."""
    return (*COMMON_PARAMS, *learner_params(), *extra)


def declare_learner(node: Node, params: Sequence[Param]) -> tuple[dict[str, Any],
                                                                   LearnerConfig]:
    """Declare a learner node's parameters (learner_node_params); return them and the config."""
    values = declare(node, params)
    names = {f.name for f in fields(LearnerConfig)}
    try:
        config = LearnerConfig(**{k: v for k, v in values.items() if k in names})
    except ValueError as error:
        raise ParameterError(str(error)) from error
    return values, config


def region_map_msg(snap: RegionSnapshot, movement_index: int, stamp) -> RegionMap:
    return RegionMap(
        stamp=stamp,
        movement_index=movement_index,
        split_count=snap.split_count,
        goal_count=snap.goal_count,
        regions=[
            Region(
                id=r.id,
                parent_id=r.parent_id,
                lower=floats(r.low),
                upper=floats(r.high),
                interest=r.interest,
                goal_count=r.goal_count,
                is_leaf=r.is_leaf,
                least_competent_goal=floats(r.least_competent_goal),
            )
            for r in snap.regions
        ],
    )


def snapshot_from_msg(msg: RegionMap) -> RegionSnapshot:
    return RegionSnapshot(
        [
            RegionSummary(
                r.id, r.parent_id, vec(r.lower), vec(r.upper), r.interest, r.goal_count,
                r.is_leaf, vec(r.least_competent_goal) if len(r.least_competent_goal) else None,
            )
            for r in msg.regions
        ],
        msg.goal_count,
        msg.split_count,
    )
