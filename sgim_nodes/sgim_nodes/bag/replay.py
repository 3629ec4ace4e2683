"""Play a run's bag back onto its topics, as `ros2 bag play` would (no rosbag2 on PyPI).

The recorded CDR bytes are published as they are, with publishers of the recorded types and
the graph's QoS, keeping the recorded time gaps divided by --rate. It first waits (briefly)
for subscribers, because records are VOLATILE: a message published before a subscriber
matched is gone for it. State topics (region_map) keep only their latest value in the
publisher, so each of them is acknowledged before the next is sent, or fast replays would
skip maps. Damaged bag parts are skipped with a warning (see bag.reader).

Usage: python -m sgim_nodes.bag.replay BAG [--rate 2.0] [--topics movements goals] [--ros-args ...]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from sgim_nodes.bag.reader import NotABagError, RawRecord, read_raw
from sgim_nodes.bag.types import STATE_TOPICS

ACK_TIMEOUT = 5.0  # seconds to wait at the end for every subscriber to acknowledge


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="replay",
        description="Play a bag back onto its topics, keeping the recorded time gaps / RATE.",
        epilog="ROS arguments may follow --ros-args, e.g. --ros-args -r __ns:=/replayed",
    )
    parser.add_argument("bag", type=Path, help="bag directory (or one .mcap / .db3 file)")
    parser.add_argument("--rate", type=float, default=1.0,
                        help="playback speed factor (2.0: twice as fast); default 1.0")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC",
                        help="only these topics (full name or last component, e.g. movements)")
    parser.add_argument("--wait-subscribers", type=float, default=2.0, metavar="SECONDS",
                        help="wait up to this long for a subscriber on every topic (default 2)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


def load(bag: Path, topics: list[str] | None) -> list[RawRecord]:
    """The records to play, with every reading problem printed as a warning."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        records = list(read_raw(bag, topics))
    for w in caught:
        print(f"replay: warning: {w.message}", file=sys.stderr)
    return records


def offsets(records: list[RawRecord], rate: float) -> list[float]:
    """Seconds after the start at which each record is due: recorded gaps divided by rate."""
    t0 = records[0].timestamp_ns if records else 0
    return [(r.timestamp_ns - t0) / 1e9 / rate for r in records]


def play(records: list[RawRecord], rate: float, wait_subscribers: float,
         quiet: bool = False, args: list[str] | None = None) -> int:
    """Publish the records in a fresh rclpy context; returns the number published."""
    import rclpy
    from rclpy.duration import Duration
    from tqdm import tqdm

    from sgim_nodes.nodes.recorder import ros_message_class, topic_qos

    rclpy.init(args=args)
    node = rclpy.create_node("replay")
    published = 0
    try:
        pubs = {}
        for topic, msgtype in {r.topic: r.msgtype for r in records}.items():
            pubs[topic] = node.create_publisher(ros_message_class(msgtype), topic,
                                                topic_qos(topic))
        deadline = time.monotonic() + wait_subscribers
        while (rclpy.ok() and time.monotonic() < deadline
               and any(p.get_subscription_count() == 0 for p in pubs.values())):
            time.sleep(0.02)
        if lonely := [t for t, p in pubs.items() if p.get_subscription_count() == 0]:
            print(f"replay: no subscriber yet on {', '.join(lonely)}: playing anyway",
                  file=sys.stderr)
        bar = tqdm(total=len(records), unit="msg", disable=quiet, file=sys.stderr)
        start = time.monotonic()
        for record, due in zip(records, offsets(records, rate), strict=True):
            target = start + due
            while rclpy.ok() and (left := target - time.monotonic()) > 0:
                time.sleep(min(left, 0.1))
            if not rclpy.ok():
                break
            pub = pubs[record.topic]
            pub.publish(record.data)
            if record.topic.rsplit("/", 1)[-1] in STATE_TOPICS:
                pub.wait_for_all_acked(Duration(seconds=1.0))
            published += 1
            bar.update()
        bar.close()
        for pub in pubs.values():
            if rclpy.ok():
                pub.wait_for_all_acked(Duration(seconds=ACK_TIMEOUT))
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return published


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    ros_args: list[str] = []
    if "--ros-args" in argv:
        cut = argv.index("--ros-args")
        argv, ros_args = argv[:cut], argv[cut:]
    parser = _parser()
    options = parser.parse_args(argv)
    if not options.rate > 0:
        parser.error(f"--rate must be > 0, got {options.rate}")
    if options.wait_subscribers < 0:
        parser.error("--wait-subscribers must be >= 0")
    try:
        records = load(options.bag, options.topics)
    except NotABagError as error:
        print(f"replay: {error}", file=sys.stderr)
        return 2
    if not records:
        print(f"replay: nothing to play in {options.bag}"
              + (f" on topics {' '.join(options.topics)}" if options.topics else ""),
              file=sys.stderr)
        return 1
    span = (records[-1].timestamp_ns - records[0].timestamp_ns) / 1e9
    print(f"replay: {len(records)} messages on {len({r.topic for r in records})} topics, "
          f"{span:.1f} s recorded, {span / options.rate:.1f} s at rate {options.rate}",
          file=sys.stderr)
    published = play(records, options.rate, options.wait_subscribers, options.quiet,
                     ["replay", *ros_args])
    print(f"replay: published {published} of {len(records)} messages", file=sys.stderr)
    return 0 if published == len(records) else 130


if __name__ == "__main__":
    raise SystemExit(main())
