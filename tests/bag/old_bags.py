"""Bags recorded by older versions, with the message definitions of their time.

The definitions are those of `git log -p sgim_msgs/msg`: Movement before `attempt` (65711b0),
Demonstration before `content` and `help_request` (a6676a1), Region before
`least_competent_goal` (c3e19e4). A bag embeds the definitions it was written with, so writing
with a typestore that holds them makes exactly the bag such a version recorded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from sgim_nodes.bag.types import TOPICS, sgim_types
from sgim_nodes.bag.writer import BagWriter

MOVEMENT_BEFORE_ATTEMPT = """
uint8 PROCESS_GOAL_DIRECTED = 0
uint8 PROCESS_EXPLORATION = 1
uint8 PROCESS_IMITATION = 2
uint8 PROCESS_DEMONSTRATION = 3
uint8 PROCESS_RANDOM = 4
uint8 PROCESS_EVALUATION = 5
uint8 STATUS_OK = 0
uint8 STATUS_NO_CONTACT = 1
uint8 STATUS_PHYSICS_FAILURE = 2
uint8 STATUS_INVALID_ACTION = 3
builtin_interfaces/Time stamp
uint64 index
uint8 process
uint8 status
float64[] action
float64[] outcome
float64[] goal
uint64 goal_index
"""

DEMONSTRATION_BEFORE_CONTENT = """
builtin_interfaces/Time stamp
uint32 index
uint64 movement_index
float64[] action
float64[] outcome
int32 teaching_set_index
string source
"""

REGION_BEFORE_LEAST_COMPETENT_GOAL = """
int32 id
int32 parent_id
float64[] lower
float64[] upper
float64 interest
uint32 goal_count
bool is_leaf
"""

OLDER = {"sgim_msgs/msg/Movement": MOVEMENT_BEFORE_ATTEMPT,
         "sgim_msgs/msg/Demonstration": DEMONSTRATION_BEFORE_CONTENT,
         "sgim_msgs/msg/Region": REGION_BEFORE_LEAST_COMPETENT_GOAL}


def store_with(definitions: dict[str, str]) -> Typestore:
    """The Jazzy types and today's sgim_msgs, with `definitions` (type -> .msg text) instead
    of today's for those types."""
    types = sgim_types()
    for name, text in definitions.items():
        types.update(get_types_from_msg(text, name))
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(types)
    return store


def old_run(store: Typestore, n: int = 12, seed: int = 4) -> list[tuple[str, object]]:
    """(topic, message) of a short run as `store`'s types: each message gets the values below
    of the fields its type has (the older types lack some; `giver`: a field never released)."""
    rng = np.random.default_rng(seed)

    def make(msgtype: str, **values):
        names = [name for name, _ in store.fielddefs[msgtype][1]]
        return store.types[msgtype](**{name: values[name] for name in names})

    def stamp(k: int):
        return make("builtin_interfaces/msg/Time", sec=100 + k, nanosec=k)

    demo = make("sgim_msgs/msg/Demonstration", stamp=stamp(0), index=1, movement_index=n // 2,
                action=rng.uniform(-1, 1, 24), outcome=rng.uniform(-1, 1, 2),
                teaching_set_index=3, source="automatic", giver="automatic",
                content="means-and-goal", help_request=0,
                signature=np.zeros(0, dtype=np.uint8))
    region = make("sgim_msgs/msg/Region", id=0, parent_id=-1, lower=np.array([-1.0, -1.0]),
                  upper=np.array([1.0, 1.0]), interest=0.25, goal_count=2, is_leaf=True,
                  least_competent_goal=np.zeros(0))
    out: list[tuple[str, object]] = []
    for i in range(1, n + 1):
        if i == n // 2 + 1:
            out += [("demonstrations", demo), ("demonstrations_taken", demo)]
        out.append(("movements", make(
            "sgim_msgs/msg/Movement", stamp=stamp(i), index=i, process=2 if i == n // 2 + 1
            else 0, status=0, action=rng.uniform(-1, 1, 24), outcome=rng.uniform(-1, 1, 2),
            goal=rng.uniform(-1, 1, 2), goal_index=1, attempt=0,
            signature=np.zeros(0, dtype=np.uint8))))
    out.append(("region_map", make(
        "sgim_msgs/msg/RegionMap", stamp=stamp(n), movement_index=n, split_count=0,
        goal_count=2, regions=[region])))
    out.append(("run_status", make(
        "sgim_msgs/msg/RunStatus", stamp=stamp(n + 1), learner="sgim-d", seed=seed,
        movement_index=n, total_movements=n, state=1, message="done")))
    return out


def write_old_bag(path: Path, store: Typestore, messages: list[tuple[str, object]],
                  types: dict[str, str] | None = None) -> Path:
    """Write (topic, message) pairs as a bag that embeds `store`'s definitions; `types`
    (topic -> type) overrides the run's topic types."""
    bag = BagWriter(path, store=store)
    types = {**TOPICS, **(types or {})}
    for k, (topic, msg) in enumerate(messages):
        bag.add_topic(f"/{topic}", types[topic])
        bag.write(f"/{topic}", 1_000_000 + 1_000 * k, store.serialize_cdr(msg, types[topic]))
    bag.close()
    return path
