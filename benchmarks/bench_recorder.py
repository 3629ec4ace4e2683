"""Recorder throughput (messages/s), worst-case loss of movements on SIGKILL, files per bag.

Why: the recorder must keep up with the graph's bursts, issue 7 asks how much a killed
recorder can lose, and issue 12 how many files a run's bag makes. Four figures:
  1. the bag writer alone, in-process (the ceiling set by rosbags and the checkpoints), and
     the files of a 5000-movement bag;
  2. the recorder node over ROS: a burst of N movements published as fast as rclpy can,
     timed until the recorder has written the last one (its exit minus its finish grace);
  3. SIGKILL at random moments while movements are published at --kill-rate per second:
     lost = published before the kill - recorded in the bag (in-flight DDS data included).

    source ros_ws/env.sh && python benchmarks/bench_recorder.py [--burst 5000] [--kills 5]
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO), str(REPO / "sgim_nodes")]

from sgim_nodes.bag.reader import NotABagError, load_run  # noqa: E402
from sgim_nodes.bag.types import typestore  # noqa: E402
from sgim_nodes.bag.writer import BagWriter  # noqa: E402
from sgim_nodes.core.learner_registry import SGIM_D  # noqa: E402
from sgim_nodes.graph.domain import isolated_ros_environment, reserve_domain  # noqa: E402

GRACE = 0.5  # finish_grace given to the recorder


def writer_alone(tmp: Path, n: int, chunk_messages: int) -> None:
    import numpy as np

    ts = typestore()
    movement = ts.types["sgim_msgs/msg/Movement"]
    msg = movement(stamp=ts.types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), index=1,
                   process=0, status=0, action=np.zeros(24), outcome=np.zeros(2),
                   goal=np.zeros(2), goal_index=1, attempt=0)
    raw = ts.serialize_cdr(msg, movement.__msgtype__)
    for storage in ("mcap", "sqlite3"):
        bag = BagWriter(tmp / f"alone_{storage}", storage=storage,
                        chunk_messages=chunk_messages, chunk_seconds=3600)
        bag.add_topic("/movements", movement.__msgtype__)
        start = time.perf_counter()
        for k in range(n):
            bag.write("/movements", k + 1, raw)
        bag.close()
        elapsed = time.perf_counter() - start
        files = sorted(p.name for p in bag.path.rglob("*") if p.is_file())
        print(f"writer alone, {storage:7s} chunks of {chunk_messages}: {n / elapsed:9.0f} msg/s "
              f"({1000 * elapsed / max(1, bag.checkpoints):.1f} ms per chunk incl. writes); "
              f"{n} movements make {len(files)} files: {', '.join(files)}")


def recorder(output: Path, env: dict, **params) -> subprocess.Popen:
    args = [sys.executable, "-m", "sgim_nodes.nodes.recorder", "--ros-args",
            "-p", f"output:={output}", "-p", f"finish_grace:={GRACE}"]
    for name, value in params.items():
        args += ["-p", f"{name}:={value}"]
    return subprocess.Popen(args, env=env, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)


class Publisher:
    def __init__(self) -> None:
        import rclpy

        from sgim_msgs.msg import Movement, RunStatus
        from sgim_ros import qos

        # A fresh context (DDS participant) per run: a killed recorder's reader stays matched
        # to an old participant until its lease expires, which would fool wait_matched().
        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node("bench_recorder", context=self.context)
        self.movements = self.node.create_publisher(Movement, "/movements", qos.RECORDS)
        self.status = self.node.create_publisher(RunStatus, "/run_status", qos.RECORDS)
        self.Movement, self.RunStatus = Movement, RunStatus

    def wait_matched(self, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while self.movements.get_subscription_count() == 0 or \
                self.status.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                raise RuntimeError("the recorder did not subscribe")
            time.sleep(0.02)

    def movement(self, index: int):
        return self.Movement(index=index, action=[0.1] * 24, outcome=[0.2, 0.3], goal=[0.0, 0.0],
                             goal_index=1)

    def close(self) -> None:
        import rclpy

        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def throughput(tmp: Path, env: dict, pub: Publisher, n: int) -> None:
    child = recorder(tmp / "burst", env)
    pub.wait_matched()
    messages = [pub.movement(i) for i in range(1, n + 1)]
    start = time.perf_counter()
    for msg in messages:
        pub.movements.publish(msg)
    published = time.perf_counter() - start
    pub.status.publish(pub.RunStatus(learner=SGIM_D, movement_index=n, total_movements=n,
                                     state=pub.RunStatus.STATE_FINISHED))
    try:
        child.wait(timeout=300)
    except subprocess.TimeoutExpired:
        os.killpg(child.pid, signal.SIGKILL)
        raise
    recorded = time.perf_counter() - start - GRACE
    count = len(load_run(tmp / "burst", ["movements"]).movements)
    print(f"recorder over ROS: {n} movements published in {published:.2f} s "
          f"({n / published:.0f} msg/s), recorded in {recorded:.2f} s "
          f"({count / recorded:.0f} msg/s), {count}/{n} in the bag")


def kills(tmp: Path, env: dict, trials: int, rate: float,
          chunk_messages: int, chunk_seconds: float) -> None:
    losses = []
    rng = random.Random(0)
    for trial in range(trials):
        bag = tmp / f"killed_{rate:.0f}_{trial}"
        child = recorder(bag, env, chunk_messages=chunk_messages, chunk_seconds=chunk_seconds)
        pub = Publisher()
        pub.wait_matched()
        kill_after = rng.randint(int(rate), int(3 * rate))  # 1 to 3 s into the run
        start = time.monotonic()
        for k in range(kill_after):
            delay = start + k / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            pub.movements.publish(pub.movement(k + 1))
        os.killpg(child.pid, signal.SIGKILL)
        child.wait()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                count = len(load_run(bag, ["movements"]).movements)
            except NotABagError:  # killed before it finished any part
                count = 0
        losses.append(kill_after - count)
        pub.close()
    bound = min(chunk_messages, rate * chunk_seconds)
    print(f"SIGKILL x{trials} at {rate:.0f} movements/s (chunks of {chunk_messages} msgs or "
          f"{chunk_seconds} s): lost {losses}, worst {max(losses)} "
          f"(design bound ~{bound:.0f} + in-flight)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--burst", type=int, default=5000, help="movements in the burst")
    parser.add_argument("--kills", type=int, default=5, help="SIGKILL trials per rate")
    parser.add_argument("--kill-rates", type=float, nargs="*", default=[50.0, 1000.0],
                        help="movements/s published during the SIGKILL trials")
    parser.add_argument("--chunk-messages", type=int, default=250)
    parser.add_argument("--chunk-seconds", type=float, default=0.5)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmpdir, reserve_domain() as domain:
        tmp = Path(tmpdir)
        writer_alone(tmp, args.burst, args.chunk_messages)
        os.environ.update(isolated_ros_environment(domain.domain_id))
        env = dict(os.environ)
        pub = Publisher()
        try:
            throughput(tmp, env, pub, args.burst)
        finally:
            pub.close()
        for rate in args.kill_rates if args.kills > 0 else ():
            kills(tmp, env, args.kills, rate, args.chunk_messages, args.chunk_seconds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
