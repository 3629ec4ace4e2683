"""ROS 2 node that records every topic of a run into a rosbag2 bag (MCAP by default).

Messages are taken as raw CDR bytes (`raw=True`) and written as they are: no deserialisation
on the hot path, and the bag holds exactly what crossed the wire. The bag is written by
bag.writer.SplitBagWriter as a sequence of small finished files, because rosbags' Writer only
leaves a readable file when closed: a SIGKILL loses at most the open part (`split_messages`
messages or the last `split_seconds`), Ctrl-C, SIGINT and SIGTERM lose nothing (the part is
closed in a finally). A final RunStatus (FINISHED or ABORTED) ends the recording once the
movements up to its count are in (topics race each other) and the graph has been quiet for
`finish_grace` (30 s at most).

Measured (benchmarks/bench_recorder.py, defaults 0.5 s / 250 messages, 2 shared cores):
about 4,300 movements/s recorded from a 5,000-message burst, none dropped; SIGKILL at random
moments lost at worst 30 movements at 50 movements/s (a real run's pace) and 229 at
1,000 movements/s, within the design bound min(split_messages, rate x (split_seconds + timer
tick 0.125 s)) plus what DDS still had in flight.

Interfaces (relative names, see docs/node_graph.md):
  subscribes  movements, goals, competences, demonstrations, evaluations, run_status (RECORDS),
              region_map (LATEST_STATE durability, keep-all so no map is skipped)
Parameters: output, storage, split_seconds, split_messages, stop_on_finish, finish_grace.
"""

from __future__ import annotations

import importlib
import sys
import time

from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile
from rclpy.serialization import deserialize_message

from sgim_msgs.msg import Movement, RunStatus
from sgim_msgs.srv import RecorderReady
from sgim_nodes.bag.types import STATE_TOPICS, TOPICS
from sgim_nodes.bag.writer import STORAGES, BagWriteError, SplitBagWriter
from sgim_ros import qos
from sgim_ros.entry import run_node
from sgim_ros.params import Param, declare, one_of, positive

FINISH_LIMIT = 30.0  # seconds after the final status at which the recorder stops regardless
PARAMS = (
    Param("output", "", "bag directory to create", lambda v: bool(v.strip()),
          "a path that does not exist yet"),
    Param("storage", "mcap", "storage format of the bag", one_of(*STORAGES),
          f"one of {', '.join(STORAGES)}"),
    Param("split_seconds", 0.5, "a bag part is finished at least this often while messages "
          "arrive (worst-case loss on SIGKILL in time)", positive, "> 0"),
    Param("split_messages", 250, "a bag part is finished after this many messages (worst-case "
          "loss on SIGKILL in messages)", lambda v: v >= 1, ">= 1"),
    Param("stop_on_finish", True, "finish the bag and exit 0 after a FINISHED or ABORTED "
          "run status, once the movements up to its count are recorded"),
    Param("finish_grace", 1.0, "seconds without messages after the final run status before "
          f"exiting, so that trailing messages are recorded (at most {FINISH_LIMIT:.0f} s)",
          positive, "> 0"),
)
FINAL_STATES = (RunStatus.STATE_FINISHED, RunStatus.STATE_ABORTED)
PROGRESS_PERIOD = 10.0  # seconds between progress lines in the log


def ros_message_class(msgtype: str) -> type:
    """The rclpy class of a rosbags type name such as 'sgim_msgs/msg/Movement'."""
    try:
        package, kind, name = msgtype.split("/")
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ValueError, ImportError, AttributeError) as error:
        raise ValueError(f"no ROS message class for type {msgtype!r}: {error}") from None


def topic_qos(topic: str, *, keep_all: bool = False) -> QoSProfile:
    """The graph's QoS for a topic (by its last name component)."""
    if topic.rsplit("/", 1)[-1] not in STATE_TOPICS:
        return qos.RECORDS
    if not keep_all:
        return qos.LATEST_STATE
    return QoSProfile(
        history=HistoryPolicy.KEEP_ALL,
        depth=1,
        reliability=qos.LATEST_STATE.reliability,
        durability=qos.LATEST_STATE.durability,
    )


class RecorderNode(Node):
    def __init__(self) -> None:
        super().__init__("recorder")
        p = declare(self, PARAMS)
        self.stop_on_finish = p["stop_on_finish"]
        self.finish_grace = p["finish_grace"]
        self.bag = SplitBagWriter(
            p["output"], storage=p["storage"], split_seconds=p["split_seconds"],
            split_messages=p["split_messages"],
        )
        self.counts: dict[str, int] = {}
        self.errors = 0
        self._finish_at: float | None = None
        self._finish_limit = 0.0
        self._last_movement: bytes | None = None
        self._max_index = 0  # highest movement index seen, tracked once the run is over
        self._target_index = 0  # the final RunStatus' movement count
        self._last_progress = time.monotonic()
        self._names: dict[str, str] = {}
        self._record_subs: dict[str, object] = {}
        for name, msgtype in TOPICS.items():
            sub = self._record_subs[name] = self.create_subscription(
                ros_message_class(msgtype), name,
                lambda raw, topic=name: self._on_message(topic, raw),
                topic_qos(name, keep_all=True), raw=True,
            )
            self._names[name] = sub.topic_name  # resolved: the namespace is recorded too
            self.bag.add_topic(sub.topic_name, msgtype)
            self.counts[name] = 0
        self.create_timer(min(0.25, p["split_seconds"] / 4), self._tick)
        self.create_service(RecorderReady, "recorder_ready", self._ready)
        self.get_logger().info(
            f"recording {len(TOPICS)} topics into {self.bag.path} ({p['storage']}, a part every "
            f"{p['split_seconds']} s or {p['split_messages']} messages)"
        )

    def _ready(self, request: RecorderReady.Request, response: RecorderReady.Response):
        """Matched, not merely discovered: only a matched publisher's messages reach the bag."""
        missing = []
        for topic, wanted in zip(request.topics, request.publishers, strict=False):
            sub = self._record_subs.get(topic)
            have = -1 if sub is None else sub.get_publisher_count()
            if have < wanted:
                missing.append(f"{topic} ({have}/{wanted})")
        response.ready = not missing
        response.message = "" if not missing else "not yet matched: " + ", ".join(missing)
        return response

    def _on_message(self, name: str, raw: bytes) -> None:
        now = self.get_clock().now().nanoseconds
        try:
            self.bag.write(self._names[name], now, raw)
        except Exception as error:  # a disk error must not end the recording
            self.errors += 1
            self.get_logger().error(f"could not write a {name} message: {error}")
            return
        self.counts[name] += 1
        if name == "movements":
            self._last_movement = raw
            if self._finish_at is not None:
                self._max_index = max(self._max_index, self._movement_index(raw))
        if self._finish_at is not None:  # trailing messages push the exit back
            self._finish_at = time.monotonic() + self.finish_grace
        if name == "run_status" and self.stop_on_finish and self._finish_at is None:
            status = deserialize_message(raw, RunStatus)
            if status.state in FINAL_STATES:
                self._start_finishing(status)

    @staticmethod
    def _movement_index(raw: bytes) -> int:
        return int(deserialize_message(raw, Movement).index)

    def _start_finishing(self, status: RunStatus) -> None:
        """Exit once the movements up to the status' count are in (topics race each other)
        and the graph has been quiet for finish_grace, or after FINISH_LIMIT at the latest."""
        start = time.monotonic()
        self._finish_limit = start + max(FINISH_LIMIT, 10 * self.finish_grace)
        self._finish_at = start + self.finish_grace
        self._target_index = int(status.movement_index)
        if self._last_movement is not None:
            self._max_index = self._movement_index(self._last_movement)
        self.get_logger().info(
            f"run over (state {status.state} at movement {status.movement_index}): "
            "finishing the bag")

    def _tick(self) -> None:
        try:
            self.bag.maybe_split()
        except Exception as error:
            self.errors += 1
            self.get_logger().error(f"could not finish a bag part: {error}")
        if time.monotonic() - self._last_progress >= PROGRESS_PERIOD:
            self._last_progress = time.monotonic()
            self.get_logger().info(f"recorded {self.summary()}")

    @property
    def finished(self) -> bool:
        if self._finish_at is None:
            return False
        now = time.monotonic()
        if now >= self._finish_limit:
            if self._max_index < self._target_index:
                self.get_logger().warning(
                    f"stopping without movements {self._max_index + 1}..{self._target_index}")
            return True
        return now >= self._finish_at and self._max_index >= self._target_index

    def summary(self) -> str:
        counts = ", ".join(f"{n} {k}" for k, n in self.counts.items() if n)
        return f"{self.bag.messages_written} messages ({counts or 'none'})"

    def close_bag(self) -> None:
        self.bag.close()
        self.get_logger().info(f"bag {self.bag.path} closed: {self.summary()}")

    @property
    def exit_code(self) -> int:
        return 1 if self.errors else 0

    def destroy_node(self) -> None:
        self.close_bag()  # however the node ends: the open part becomes a finished file
        super().destroy_node()


def _usage() -> str:
    lines = [
        "usage: recorder [--ros-args -p NAME:=VALUE ...]",
        "",
        "Record every topic of a run (docs/node_graph.md) into a rosbag2 bag.",
        "Example: ros_ws/ros2run.sh sgim_nodes recorder --ros-args -p output:=runs/run1",
        "",
        "parameters:",
    ]
    for p in PARAMS:
        req = f"; {p.requirement}" if p.requirement else ""
        lines.append(f"  {p.name} (default {p.default!r}{req}): {p.description}")
    return "\n".join(lines)


def main(args: list[str] | None = None) -> int:
    argv = sys.argv[1:] if args is None else args
    if any(a in ("-h", "--help") for a in argv[: argv.index("--ros-args")
                                                if "--ros-args" in argv else None]):
        print(_usage())
        return 0
    return run_node(RecorderNode, args, refusals=(BagWriteError,))


if __name__ == "__main__":
    raise SystemExit(main())
