"""Play a run's bag back onto its topics, as `ros2 bag play` would (no rosbag2 on PyPI).

The recorded CDR bytes are published as they are, with publishers of the recorded types and
the graph's QoS, keeping the recorded time gaps divided by --rate. A record from a bag of an
older version, whose type has gained fields since, is first re-encoded as today's type (the
new fields at their defaults, bag/schema.py), so that today's subscribers decode it; a field
removed or retyped since, or a type gone, is refused (exit 2) naming the topic and field.
Records are VOLATILE: a message published before a subscriber matched is gone for it, so
replay first waits, saying so at once, until every topic has --subscribers matched
subscriptions (default 1), for at most --wait-subscribers seconds. A listener that takes only
some topics (rviz2 on the markers, a node on /movements) is enough: once no new match has come
for SETTLE seconds, replay plays, naming the topics nobody hears. With nobody at all it
refuses to play (exit 3, naming the topics), unless --play-anyway. State topics
(region_map) keep only their latest value in the publisher, so each of them is acknowledged
before the next is sent, or fast replays would skip maps. Damaged bag parts are skipped
with a warning (see bag.reader), and records that fail validation (bag/validation.py, as
every reader) are left out and reported, unless --include-quarantined plays them as
recorded (an audit of an attack).

Usage: python -m sgim_nodes.bag.replay BAG [--rate 2.0] [--topics movements goals] [--ros-args ...]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

from sgim_nodes.bag.reader import NotABagError, RawRecord, limits_for, read_raw
from sgim_nodes.bag.record_checks import Problem
from sgim_nodes.bag.schema import SchemaError, Upgrader
from sgim_nodes.bag.types import STATE_TOPICS, TOPICS
from sgim_nodes.bag.validation import RunValidator, summarise
from sgim_ros.command_line import BriefParser

ACK_TIMEOUT = 5.0  # seconds to wait at the end for every subscriber to acknowledge
# Seconds without a new match, once some topics have their subscribers, before the others are
# taken as unheard: one listener's subscriptions match within a second or two of each other.
SETTLE = 3.0
NO_SUBSCRIBERS = 3  # exit code: the expected subscribers never matched


def _parser() -> argparse.ArgumentParser:
    parser = BriefParser(
        prog="replay",
        description="Play a bag back onto its topics, keeping the recorded time gaps / RATE. "
                    "A bag of an older version plays as today's messages (fields added "
                    "since at their defaults).",
        epilog="ROS arguments may follow --ros-args, e.g. --ros-args -r __ns:=/replayed",
    )
    parser.add_argument("bag", type=Path, help="bag directory (or one .mcap / .db3 file)")
    parser.add_argument("--rate", type=float, default=1.0,
                        help="playback speed factor (2.0: twice as fast); default 1.0")
    parser.add_argument("--topics", nargs="+", metavar="TOPIC",
                        help="only these topics (full name or last component, e.g. movements)")
    parser.add_argument("--subscribers", type=int, default=1, metavar="N",
                        help="matched subscriptions every topic must have before playing "
                             "(default 1; 0: do not wait)")
    parser.add_argument("--wait-subscribers", type=float, default=30.0, metavar="SECONDS",
                        help="how long to wait for them (default 30); then replay plays to "
                             "the topics that have them, or refuses when none has, exit "
                             f"{NO_SUBSCRIBERS}")
    parser.add_argument("--play-anyway", action="store_true",
                        help="play even if nobody subscribes (e.g. rviz2 started later)")
    parser.add_argument("--include-quarantined", action="store_true",
                        help="also play records that fail validation (exactly as recorded)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    return parser


def load(bag: Path, topics: list[str] | None, include_quarantined: bool = False
         ) -> list[RawRecord]:
    """The records to play, as today's messages, with every reading problem printed as a
    warning. A record of an older schema is converted (bag/schema.py; SchemaError when it
    cannot be); records that fail validation are left out (and reported) unless
    `include_quarantined`, which keeps them as recorded."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        validator = RunValidator(limits_for(bag))
        records = list(read_raw(bag, topics, on_gap=validator.resync))
    for w in caught:
        print(f"replay: warning: {w.message}", file=sys.stderr)
    upgrader = Upgrader()
    kept = []
    for record in records:
        name = record.topic.rsplit("/", 1)[-1]
        validated = record.msgtype == TOPICS.get(name) and not include_quarantined
        upgrader.is_current(record)  # SchemaError: nothing is played
        try:
            record = upgrader.upgrade(record)
            message = upgrader.decode(record) if validated else None
        except Exception as error:
            if include_quarantined:  # exactly as recorded
                kept.append(record)
            else:
                validator.quarantine(name, -1, Problem("undecodable", str(error)))
            continue
        if validated and not validator.admit(name, message).ok:
            continue
        kept.append(record)
    if validator.quarantined:
        print(f"replay: {len(validator.quarantined)} record(s) fail validation and are not "
              "played (--include-quarantined plays them): "
              + "; ".join(summarise(validator.quarantined)), file=sys.stderr)
    return kept


def wait_for_subscribers(pubs: dict, wanted: int, timeout: float, ok,
                         settle: float = SETTLE) -> list[str]:
    """Wait until every publisher has `wanted` matched subscriptions, or, once some have,
    until no new one has matched for `settle` seconds; the topics that lack them when it
    stops (empty when all matched)."""
    deadline = time.monotonic() + timeout
    matched: set[str] = set()
    changed = time.monotonic()
    while ok() and time.monotonic() < deadline:
        now = {t for t, p in pubs.items() if p.get_subscription_count() >= wanted}
        if len(now) == len(pubs):
            return []
        if now != matched:
            matched, changed = now, time.monotonic()
        elif matched and time.monotonic() - changed >= settle:
            break
        time.sleep(0.02)
    return [f"{t} ({p.get_subscription_count()}/{wanted})" for t, p in pubs.items()
            if p.get_subscription_count() < wanted]


def offsets(records: list[RawRecord], rate: float) -> list[float]:
    """Seconds after the start at which each record is due: recorded gaps divided by rate."""
    t0 = records[0].timestamp_ns if records else 0
    return [(r.timestamp_ns - t0) / 1e9 / rate for r in records]


def play(records: list[RawRecord], rate: float, wait_subscribers: float,
         quiet: bool = False, args: list[str] | None = None, subscribers: int = 1,
         play_anyway: bool = False) -> int:
    """Publish the records in a fresh rclpy context; returns the number published, or -1
    when the expected subscribers did not match in time (and not `play_anyway`)."""
    import rclpy
    from rclpy.duration import Duration
    from tqdm import tqdm

    from sgim_ros.interfaces import ros_message_class, topic_qos

    rclpy.init(args=args)
    node = rclpy.create_node("replay")
    published = 0
    try:
        pubs = {}
        for topic, msgtype in {r.topic: r.msgtype for r in records}.items():
            pubs[topic] = node.create_publisher(ros_message_class(msgtype), topic,
                                                topic_qos(topic))
        if subscribers and wait_subscribers and not all(
                p.get_subscription_count() >= subscribers for p in pubs.values()):
            print(f"replay: waiting up to {wait_subscribers:g} s for subscribers on the "
                  f"{len(pubs)} topics (start them now: rviz2, your nodes; --play-anyway "
                  "--wait-subscribers 0 plays at once)", file=sys.stderr)
        lonely = wait_for_subscribers(pubs, subscribers, wait_subscribers, rclpy.ok)
        if lonely and len(lonely) < len(pubs):  # someone listens: play to them
            print(f"replay: nobody hears {', '.join(lonely)}; playing to the subscribers of "
                  "the others", file=sys.stderr)
        elif lonely:
            if not play_anyway:
                print(f"replay: after {wait_subscribers:g} s, too few subscribers on "
                      f"{', '.join(lonely)}: not playing (a record published before its "
                      "subscriber matches is lost to it). Start the subscribers first, wait "
                      "longer (--wait-subscribers) or pass --play-anyway", file=sys.stderr)
                return -1
            print(f"replay: too few subscribers on {', '.join(lonely)}: playing anyway",
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
    if options.wait_subscribers < 0 or options.subscribers < 0:
        parser.error("--wait-subscribers and --subscribers must be >= 0")
    try:
        records = load(options.bag, options.topics, options.include_quarantined)
    except (NotABagError, SchemaError) as error:
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
                     ["replay", *ros_args], options.subscribers, options.play_anyway)
    if published < 0:
        return NO_SUBSCRIBERS
    print(f"replay: published {published} of {len(records)} messages", file=sys.stderr)
    return 0 if published == len(records) else 130


if __name__ == "__main__":
    raise SystemExit(main())
