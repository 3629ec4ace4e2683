"""Starting the recorder and publishing a run's topics from the test process."""

from __future__ import annotations

import random
import time
from pathlib import Path

from tests.conftest import PYTHON, REPO, ROS2RUN

INSTALLED = REPO / "ros_ws" / "install" / "sgim_nodes" / "lib" / "sgim_nodes"


def node_command(executable: str, module: str) -> list[str]:
    """`ros2run.sh sgim_nodes EXE` once the entry point is installed, else `python -m`."""
    if (INSTALLED / executable).exists():
        return [ROS2RUN, "sgim_nodes", executable]
    return [PYTHON, "-m", module]


def recorder_command(output: Path, **params) -> list[str]:
    args = [*node_command("recorder", "sgim_nodes.nodes.recorder"), "--ros-args",
            "-p", f"output:={output}"]
    for name, value in params.items():
        args += ["-p", f"{name}:={value}"]
    return args


def publishers(client) -> dict:
    """One publisher per recorded topic, with the graph's QoS."""
    from sgim_nodes.bag.types import TOPICS
    from sgim_ros.interfaces import ros_message_class, topic_qos

    return {name: client.node.create_publisher(ros_message_class(t), f"/{name}", topic_qos(name))
            for name, t in TOPICS.items()}


def wait_matched(client, pubs: dict, timeout: float = 30.0) -> None:
    assert client.spin_until(
        lambda: all(p.get_subscription_count() > 0 for p in pubs.values()), timeout
    ), "the recorder did not subscribe to every topic"


def movement(index: int, rng: random.Random):
    from sgim_msgs.msg import Movement

    return Movement(index=index, process=Movement.PROCESS_GOAL_DIRECTED,
                    status=Movement.STATUS_OK, action=[rng.uniform(-1, 1) for _ in range(24)],
                    outcome=[rng.uniform(-1, 1), rng.uniform(-1, 1)], goal=[0.5, -0.5],
                    goal_index=index // 10 + 1)


def paced(count: int, per_second: float):
    """Yield 0..count-1 no faster than per_second (sleeping in small batches)."""
    start = time.monotonic()
    for k in range(count):
        if k % 10 == 0:
            delay = start + k / per_second - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        yield k
