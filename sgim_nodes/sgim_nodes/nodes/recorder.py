"""ROS 2 node that records every topic of a run into a rosbag2 bag of one MCAP file.

Messages are taken as raw CDR bytes (`raw=True`) and written as they are: the bag holds exactly
what crossed the wire, rogue records included, so an audit can see an attack. The bag is one
storage file written by bag.writer.BagWriter in chunks: every `chunk_seconds` or
`chunk_messages` the chunk is closed and flushed, so a SIGKILL loses at most that much and the
file reads up to its last chunk; Ctrl-C, SIGINT and SIGTERM lose nothing (the file is closed in
a finally, with its summary and metadata.yaml).

Every record is also validated as the readers and the live nodes validate it
(bag/validation.py, with the run's limits from the shared parameter file). A record that fails
is recorded all the same, logged with its topic, index and reason, and counted; the counts go
to `<output>.quarantine.yaml` beside the bag (rewritten as they change, and at the end), which
the launcher copies into metadata.yaml. Only a valid final RunStatus ends the recording: once
the valid movements up to its count are in (topics race each other) and the graph has been
quiet for `finish_grace` (30 s at most).

A write error (a full disk, a file-size limit, an I/O error) ends the node at once with exit
code 3 (WRITE_FAILED) after logging why and how much the bag holds; the quarantine file says
it too (`write_error`), so the launcher fails the run with the reason.

Measured (benchmarks/bench_recorder.py): see docs/reliability.md.

Interfaces (relative names, see docs/reference.md):
  subscribes  every topic of bag.types.TOPICS (RECORDS), region_map (LATEST_STATE durability,
              keep-all so no map is skipped), and the viewers' topics (bag.types.VIEW_TOPICS:
              pace_state, markers/*), recorded as they come, without validation
  serves      recorder_ready (sgim_msgs/srv/RecorderReady)
Parameters: see PARAMS (and `recorder --help`).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any

import yaml
from rclpy.node import Node
from rclpy.serialization import deserialize_message

from sgim_msgs.msg import RunStatus
from sgim_nodes.bag.record_checks import LIMITS_KEY, Limits, teaching_set_size
from sgim_nodes.bag.run_folder import QUARANTINE_SUFFIX
from sgim_nodes.bag.types import RECORDED_TOPICS, TOPICS
from sgim_nodes.bag.validation import RunValidator
from sgim_nodes.bag.writer import STORAGES, BagWriteError, BagWriter
from sgim_ros.host import NodeEntry
from sgim_ros.interfaces import declared, serves, subscribes
from sgim_ros.params import Param, at_least, declare, non_negative, one_of, positive
from sgim_ros.ready import serve_ready
from sim_bridge.data_params import TEACHING_SET_FILE

FINISH_LIMIT = 30.0  # seconds after the final status at which the recorder stops regardless
WRITE_FAILED = 3  # exit code: the bag could not be written (the launcher fails the run)
LOGGED_QUARANTINES = 20  # quarantined records logged one by one; then counted only
PARAMS = (
    Param("output", "", "bag directory to create", lambda v: bool(v.strip()),
          "a path that does not exist yet"),
    Param("storage", "mcap", "storage format of the bag", one_of(*STORAGES)),
    Param("chunk_seconds", 0.5, "the open chunk is closed and flushed at least this often "
          "while messages arrive (worst-case loss on SIGKILL, in time)", positive),
    Param("chunk_messages", 250, "the open chunk is closed and flushed after this many "
          "messages (worst-case loss on SIGKILL, in messages)", at_least(1)),
    Param("stop_on_finish", True, "close the bag and exit 0 after a valid FINISHED or ABORTED "
          "run status, once the movements up to its count are recorded"),
    Param("finish_grace", 1.0, "seconds without messages after the final run status before "
          f"exiting, so that trailing messages are recorded (at most {FINISH_LIMIT:.0f} s)",
          positive),
    # The run's limits, to validate records as every reader will (the shared parameter file
    # gives the run's own; 0 = unknown, that check is skipped).
    Param("movements", 0, "the run's movement budget, to validate indices (0: unknown)",
          non_negative),
    Param("action_size", 24, "numbers per action", at_least(1)),
    Param("outcome_size", 2, "numbers per outcome", at_least(1)),
    Param("teaching_set", "", "the teacher's teaching-set file (empty: the packaged one), to "
          "validate teaching-set indices", TEACHING_SET_FILE),
    # A resumed run's segment continues the run's counts: its first movement is the one after
    # the resume point, not movement 1 (the launcher gives every node the same two values).
    Param("resume_from", "", "run folder being resumed: the movement and goal counts of its "
          "recordings are where this segment's validation starts (empty: a new run)"),
    Param("resume_segments", 0, "how many of its recordings to read (0: all)", non_negative),
)
FINAL_STATES = (RunStatus.STATE_FINISHED, RunStatus.STATE_ABORTED)
PROGRESS_PERIOD = 10.0  # seconds between progress lines in the log


def resumed_counts(run_dir: str, segments: int = 0) -> tuple[int, int]:
    """The movement and goal counts a resumed run carries on from: the last valid ones of
    its recordings, as the arbiter's resume point counts them (0, 0 for a new run)."""
    if not run_dir:
        return 0, 0
    import warnings

    from sgim_nodes.bag.run_folder import load_run_folder

    with warnings.catch_warnings():  # the earlier segments' own reports said it already
        warnings.simplefilter("ignore")
        records = load_run_folder(run_dir, segments, topics=("movements", "goals"))
    return (max((m.index for m in records.movements), default=0),
            max((g.index for g in records.goals), default=0))


def quarantine_file(output: str | Path) -> Path:
    """Where the recorder of bag `output` writes its quarantine counts (the launcher reads
    it): beside the bag, in the run folder, e.g. runs/x/bag.quarantine.yaml."""
    output = Path(output)
    return output.with_name(output.name + QUARANTINE_SUFFIX)

# Every topic of the run (sgim_ros/interfaces.py), state topics kept whole: a bag holds each
# region map and pace state, not only the latest.
RECORDED = tuple(subscribes(name, keep_all=True) for name in RECORDED_TOPICS)
READY = serves("recorder_ready")
INTERFACES = declared(RECORDED, READY)


class RecorderNode(Node):
    def __init__(self, **node_options: Any) -> None:
        super().__init__("recorder", **node_options)
        p = declare(self, PARAMS)
        self.stop_on_finish = p["stop_on_finish"]
        self.finish_grace = p["finish_grace"]
        self.bag = BagWriter(p["output"], storage=p["storage"],
                             chunk_seconds=p["chunk_seconds"],
                             chunk_messages=p["chunk_messages"])
        movement_count, goal_count = resumed_counts(p["resume_from"], p["resume_segments"])
        self.validator = RunValidator(Limits(
            action_size=p["action_size"], outcome_size=p["outcome_size"],
            budget=p["movements"], teaching_set_size=teaching_set_size(p["teaching_set"] or None)),
            movement_count=movement_count, goal_count=goal_count)
        # Readers of this bag validate with the same limits (bag.reader.limits_for).
        self.bag.custom_data[LIMITS_KEY] = self.validator.limits.to_json()
        self._quarantine_path = quarantine_file(self.bag.path)
        self._quarantine_written = -1
        self.counts: dict[str, int] = {}
        self.write_error = ""
        self.finished, self.exit_code = False, 0
        self._finish_at: float | None = None
        self._finish_limit = 0.0
        self._target_index = 0  # the final RunStatus' movement count
        self._last_progress = time.monotonic()
        self._names: dict[str, str] = {}
        self._classes: dict[str, type] = {}
        self._record_subs: dict[str, object] = {}
        for topic in RECORDED:
            name = topic.name
            self._classes[name] = topic.interface()
            sub = self._record_subs[name] = topic.create(
                self, lambda raw, topic=name: self._on_message(topic, raw), raw=True)
            self._names[name] = sub.topic_name  # resolved: the namespace is recorded too
            self.bag.add_topic(sub.topic_name, topic.type)
            self.counts[name] = 0
        self.create_timer(min(0.25, p["chunk_seconds"] / 4), self._tick)
        # Matched, not merely discovered: only a matched publisher's messages reach the bag.
        serve_ready(self, READY, self._record_subs)
        self._write_quarantine()
        self.get_logger().info(
            f"recording {len(RECORDED_TOPICS)} topics into {self.bag.file} ({p['storage']}, "
            f"flushed every {p['chunk_seconds']} s or {p['chunk_messages']} messages)")

    def _on_message(self, name: str, raw: bytes) -> None:
        if self.finished:
            return
        now = self.get_clock().now().nanoseconds
        try:
            self.bag.write(self._names[name], now, raw)
        except Exception as error:
            self._fail(f"could not write a {name} message: {type(error).__name__}: {error}")
            return
        self.counts[name] += 1
        if name in TOPICS:  # the learner's records; the viewers' topics are only kept
            self._validate(name, raw, now)
        if self._finish_at is not None:  # trailing messages push the exit back
            self._finish_at = time.monotonic() + self.finish_grace

    def _validate(self, name: str, raw: bytes, now: int) -> None:
        try:
            message = deserialize_message(raw, self._classes[name])
        except Exception as error:
            from sgim_nodes.bag.record_checks import Problem

            self.validator.quarantine(name, -1, Problem("undecodable", str(error)), now)
            self._log_quarantine()
            return
        verdict = self.validator.admit(name, message, now)
        if not verdict.ok:
            self._log_quarantine()
        elif (name == "run_status" and self.stop_on_finish and self._finish_at is None
              and message.state in FINAL_STATES):
            self._start_finishing(message)

    def _log_quarantine(self) -> None:
        n = len(self.validator.quarantined)
        if n <= LOGGED_QUARANTINES:
            self.get_logger().warning(f"{self.validator.quarantined[-1]} (recorded in the bag, "
                                      "left out by every reader)")
            if n == LOGGED_QUARANTINES:
                self.get_logger().warning("further quarantined records are counted in "
                                          f"{self._quarantine_path.name}, not logged")

    def _start_finishing(self, status: RunStatus) -> None:
        """Exit once the movements up to the status' count are in (topics race each other)
        and the graph has been quiet for finish_grace, or after FINISH_LIMIT at the latest."""
        start = time.monotonic()
        self._finish_limit = start + max(FINISH_LIMIT, 10 * self.finish_grace)
        self._finish_at = start + self.finish_grace
        self._target_index = int(status.movement_index)
        self.get_logger().info(
            f"run over (state {status.state} at movement {status.movement_index}): "
            "finishing the bag")

    def _tick(self) -> None:
        if self.finished:
            return
        try:
            self.bag.maybe_checkpoint()
        except Exception as error:
            self._fail(f"could not flush the bag: {type(error).__name__}: {error}")
            return
        if len(self.validator.quarantined) != self._quarantine_written:
            self._write_quarantine()
        if time.monotonic() - self._last_progress >= PROGRESS_PERIOD:
            self._last_progress = time.monotonic()
            self.get_logger().info(f"recorded {self.summary()}")
        if self._finish_at is not None and self._done():
            self.finished = True

    def _done(self) -> bool:
        now = time.monotonic()
        count = self.validator.movements.count
        if now >= self._finish_limit:
            if count < self._target_index:
                self.get_logger().warning(
                    f"stopping without movements {count + 1}..{self._target_index}")
            return True
        return now >= self._finish_at and count >= self._target_index

    def _fail(self, why: str) -> None:
        """A write error: stop recording now, say why, exit WRITE_FAILED."""
        self.write_error = why
        self.finished, self.exit_code = True, WRITE_FAILED
        self.bag.abort()
        self.get_logger().error(
            f"{why}: recording stopped. The bag holds {self.bag.messages_durable} messages, "
            f"readable up to its last flushed chunk ({self.bag.file}); exit code {WRITE_FAILED}")
        self._write_quarantine()

    def _write_quarantine(self) -> None:
        """The counts the launcher puts into metadata.yaml (atomic replace; best effort)."""
        v = self.validator
        report = {
            "segment": self.bag.path.name,
            "received": dict(self.counts),
            "quarantined": v.counts(),
            "total_quarantined": len(v.quarantined),
            "re_executed_movements": list(v.superseded),
            "first_quarantined": [str(q) for q in v.quarantined[:LOGGED_QUARANTINES]],
            "write_error": self.write_error or None,
        }
        tmp = self._quarantine_path.with_name(f".{self._quarantine_path.name}.{os.getpid()}")
        try:
            tmp.write_text(yaml.safe_dump(report, sort_keys=False), encoding="utf-8")
            os.replace(tmp, self._quarantine_path)
            self._quarantine_written = len(v.quarantined)
        except OSError as error:  # a full disk: the log and the exit code still say it
            tmp.unlink(missing_ok=True)
            if not self.write_error:
                self.get_logger().warning(f"could not write {self._quarantine_path}: {error}")

    def summary(self) -> str:
        counts = ", ".join(f"{n} {k}" for k, n in self.counts.items() if n)
        quarantined = len(self.validator.quarantined)
        return (f"{self.bag.messages_written} messages ({counts or 'none'})"
                + (f", {quarantined} quarantined" if quarantined else ""))

    def close_bag(self) -> None:
        if self.write_error:
            return
        try:
            self.bag.close()
        except Exception as error:
            self._fail(f"could not close the bag: {type(error).__name__}: {error}")
            return
        self._write_quarantine()
        self.get_logger().info(f"bag {self.bag.file} closed: {self.summary()}")

    def destroy_node(self) -> None:
        self.close_bag()  # however the node ends: the file gets its summary
        super().destroy_node()


def _usage() -> str:
    lines = [
        "usage: recorder [--ros-args -p NAME:=VALUE ...]",
        "",
        "Record every topic of a run (docs/reference.md) into a rosbag2 bag of one MCAP file.",
        "Example: ros_ws/ros2run.sh sgim_nodes recorder --ros-args -p output:=runs/run1",
        f"Exit codes: 0 done, 2 bad parameters, {WRITE_FAILED} the bag could not be written.",
        "",
        "parameters:",
    ]
    for p in PARAMS:
        req = f"; {p.requirement}" if p.requirement else ""
        lines.append(f"  {p.name} (default {p.default!r}{req}): {p.description}")
    return "\n".join(lines)


ENTRY = NodeEntry(RecorderNode, refusals=(BagWriteError, OSError))
"""How this node starts, alone or beside others (sgim_ros/host.py)."""


def main(args: list[str] | None = None) -> int:
    argv = sys.argv[1:] if args is None else args
    if any(a in ("-h", "--help") for a in argv[: argv.index("--ros-args")
                                                if "--ros-args" in argv else None]):
        print(_usage())
        return 0
    return ENTRY.main(args)


if __name__ == "__main__":
    raise SystemExit(main())
