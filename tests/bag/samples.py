"""A small synthetic run as rosbags messages (no rclpy), and a writer for it.

The run mimics the node graph's contract: movements 1..n, a goal and a competence every few
movements, a help request mid-run answered by a demonstration (the teacher's checks, then the
demonstration offered, then taken by the arbiter) followed by imitation movements, region
maps, evaluations and a final RunStatus. Values are seeded so tests can rebuild the same
records directly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sgim_nodes.bag.types import TOPICS, typestore
from sgim_nodes.bag.writer import BagWriter

TS = typestore()
T = TS.types


def stamp(ns: int):
    return T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def movement(index: int, rng: np.random.Generator, process: int = 0, status: int = 0,
             attempt: int = 0):
    ok = status == 0
    return T["sgim_msgs/msg/Movement"](
        stamp=stamp(1_000 + index), index=index, process=process, status=status,
        action=rng.uniform(-1, 1, 24),
        outcome=rng.uniform(-1, 1, 2) if ok else np.zeros(0),
        goal=rng.uniform(-1, 1, 2), goal_index=index // 5 + 1, attempt=attempt,
        signature=np.zeros(0, dtype=np.uint8))


def goal(index: int, movement_index: int, rng: np.random.Generator):
    return T["sgim_msgs/msg/Goal"](stamp=stamp(7), index=index, movement_index=movement_index,
                                   point=rng.uniform(-1, 1, 2), region_id=index % 3, mode=1,
                                   strategy="")


def competence(goal_index: int, movement_index: int, rng: np.random.Generator,
               from_demonstration: bool = False, strategy: str = ""):
    return T["sgim_msgs/msg/Competence"](
        stamp=stamp(9), goal_index=goal_index, movement_index=movement_index,
        goal=rng.uniform(-1, 1, 2), reached=rng.uniform(-1, 1, 2),
        competence=float(-rng.uniform(0, 1)), movements_used=5,
        from_demonstration=from_demonstration, strategy=strategy,
        signature=np.zeros(0, dtype=np.uint8))


def region(rid: int, parent: int, lower, upper, leaf: bool):
    return T["sgim_msgs/msg/Region"](
        id=rid, parent_id=parent, lower=np.asarray(lower, float), upper=np.asarray(upper, float),
        interest=0.01 * rid, goal_count=3 * rid, is_leaf=leaf,
        least_competent_goal=np.asarray(lower, float) + 0.1)


def region_map(movement_index: int, split: bool):
    regions = [region(0, -1, [-1, -1], [1, 1], not split)]
    if split:
        regions += [region(1, 0, [-1, -1], [0, 1], True), region(2, 0, [0, -1], [1, 1], True)]
    return T["sgim_msgs/msg/RegionMap"](stamp=stamp(11), movement_index=movement_index,
                                        split_count=int(split), goal_count=movement_index // 5,
                                        regions=regions)


def demonstration(index: int, movement_index: int, rng: np.random.Generator,
                  content: str = "means-and-goal", help_request: int = 0):
    """A demonstration showing what `content` says (the other part empty)."""
    action, outcome = rng.uniform(-1, 1, 24), rng.uniform(-1, 1, 2)
    return T["sgim_msgs/msg/Demonstration"](
        stamp=stamp(13), index=index, movement_index=movement_index,
        action=np.zeros(0) if content == "goal-only" else action,
        outcome=np.zeros(0) if content == "means-only" else outcome,
        teaching_set_index=index + 4, source="automatic", content=content,
        help_request=help_request, signature=np.zeros(0, dtype=np.uint8))


def help_request(index: int, movement_index: int, rng: np.random.Generator,
                 teacher: str = "", content: str = ""):
    return T["sgim_msgs/msg/HelpRequest"](stamp=stamp(29), index=index,
                                          movement_index=movement_index,
                                          goal=rng.uniform(-1, 1, 2), teacher=teacher,
                                          content=content,
                                          signature=np.zeros(0, dtype=np.uint8))


TEACHING_ENTRIES = 8  # a turn's checks: a teaching set no smaller than any test's limits


def teacher_checks(movement_index: int, help_request: int, asked_goal, chosen: int,
                   rng: np.random.Generator) -> list:
    """A turn's TeacherChecks under the ability rule: entry `chosen` unreached and shown,
    every other reached."""
    out = []
    for k in range(TEACHING_ENTRIES):
        goal = rng.uniform(-0.9, 0.9, 2)
        landed = goal + (0.3 if k == chosen else 0.001)
        distance = float(np.sqrt(((landed - goal) ** 2).sum()))
        out.append(T["sgim_msgs/msg/TeacherCheck"](
            stamp=stamp(31), movement_index=movement_index, help_request=help_request,
            asked_goal=np.asarray(asked_goal, float), rule="ability", choice="random-unreached",
            entries=TEACHING_ENTRIES, teaching_set_index=k, goal=goal,
            action=rng.uniform(-1, 1, 24), status=0, landed=landed, own_outcomes=0,
            distance=distance, tolerance=0.05, reached=distance <= 0.05, chosen=k == chosen))
    return out


def evaluation(movement_index: int, rng: np.random.Generator):
    goals = rng.uniform(-1, 1, (3, 2))
    reached = goals + 0.1
    reached[1] = np.nan  # a failed cast
    distances = np.array([0.14, 2.83, 0.14])
    return T["sgim_msgs/msg/Evaluation"](
        stamp=stamp(17), movement_index=movement_index, mean_distance=float(distances.mean()),
        outcome_size=2, goals=goals.ravel(), reached=reached.ravel(), distances=distances)


def run_status(movement_index: int, total: int, state: int, message: str = ""):
    return T["sgim_msgs/msg/RunStatus"](stamp=stamp(19), learner="sgim-d", seed=3,
                                        movement_index=movement_index, total_movements=total,
                                        state=state, message=message)


def pace_state(movement_index: int, paused: bool, waiting: bool, message: str = ""):
    return T["sgim_msgs/msg/PaceState"](
        stamp=stamp(23), movement_index=movement_index, total_movements=300, paused=paused,
        held=paused, steps_left=0, waiting_for_teacher=waiting, wait_seconds=-1.0,
        wait_seconds_left=-1.0, teacher_period=150, message=message)


def synthetic_run(n: int = 60, seed: int = 0) -> list[tuple[str, object]]:
    """(topic, message) in publication order for an n-movement SGIM-D-like run."""
    rng = np.random.default_rng(seed)
    out: list[tuple[str, object]] = [("run_status", run_status(0, n, 0))]
    goal_count = 0
    for i in range(1, n + 1):
        if i % 5 == 1:
            goal_count += 1
            out.append(("goals", goal(goal_count, i - 1, rng)))
        if i == n // 2:  # the learner asks at count i - 1; the teacher's checks, the answer,
            # taken; its imitation
            ask = help_request(1, i - 1, rng)
            out.append(("help_requests", ask))
            demo = demonstration(1, i - 1, rng, help_request=1)
            # Their own stream: the other records keep the values they always had.
            out += [("teacher_checks", c) for c in teacher_checks(
                i - 1, 1, ask.goal, demo.teaching_set_index, np.random.default_rng([seed, 31]))]
            out += [("demonstrations", demo), ("demonstrations_taken", demo)]
        process = 2 if n // 2 <= i < n // 2 + 5 else (1 if i % 4 == 0 else 0)
        out.append(("movements", movement(i, rng, process, status=1 if i % 7 == 0 else 0)))
        if i % 5 == 0:
            out.append(("competences", competence(goal_count, i, rng, i == n // 2 + 4)))
            out.append(("region_map", region_map(i, split=i > n // 2)))
        if i % 20 == 0:
            out.append(("evaluations", evaluation(i, rng)))
    out.append(("run_status", run_status(n, n, 1, "done")))
    return out


def write_bag(path: Path, messages: list[tuple[str, object]], **writer_kwargs) -> Path:
    """Write (topic, message) pairs with the bag writer, topics as "/name"."""
    bag = BagWriter(path, **writer_kwargs)
    for topic, msgtype in TOPICS.items():
        bag.add_topic(f"/{topic}", msgtype)
    for k, (topic, msg) in enumerate(messages):
        bag.write(f"/{topic}", 1_000_000 + k, TS.serialize_cdr(msg, msg.__msgtype__))
    bag.close()
    return path
