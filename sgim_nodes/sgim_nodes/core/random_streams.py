"""One independent random stream per component of the learner, all derived from the run's seed.

In the node graph each component (goal generator, explorer, imitation, arbiter, teacher) is a
process of its own with its own generator. Giving every component its own named stream in the
single-process learner too means both draw exactly the same numbers for the same seed, however
the processes interleave: this is what lets the graph reproduce a single-process run.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

SEED_MAX = 2**32 - 1
"""The largest seed of a run. numpy would take any integer >= 0, but the node graph carries the
seed in a uint32 (RunStatus.seed); one range everywhere keeps a seed that `learn` takes one the
graph takes too (sgim_ros.params.SEED_MAX is the same number, for the nodes and the launcher)."""
STREAM_NAMES = ("goals", "explorer", "imitation", "random", "teacher", "teacher-world",
                "strategies", "experts")
"""Appending a name keeps every earlier stream: child i of a SeedSequence does not depend on
how many children are spawned."""


def component_rng(seed: int, name: str) -> np.random.Generator:
    """The generator of component `name` for run `seed` (same in every process)."""
    if name not in STREAM_NAMES:
        raise ValueError(f"unknown random stream {name!r}; known: {STREAM_NAMES}")
    if not 0 <= seed <= SEED_MAX:
        raise ValueError(f"seed must be in 0..{SEED_MAX}, got {seed}")
    children = np.random.SeedSequence(seed).spawn(len(STREAM_NAMES))
    return np.random.default_rng(children[STREAM_NAMES.index(name)])


def member_rng(seed: int, name: str, member: str) -> np.random.Generator:
    """The generator of one member of stream `name` (e.g. teacher "west" of "experts"): a
    child of that stream's seed keyed by the member's name, so that adding, removing or
    reordering members leaves every other member's draws unchanged."""
    component_rng(seed, name)  # checks the name and the seed
    child = np.random.SeedSequence(seed).spawn(len(STREAM_NAMES))[STREAM_NAMES.index(name)]
    key = zlib.crc32(member.encode("utf-8"))
    return np.random.default_rng(np.random.SeedSequence(child.entropy,
                                                        spawn_key=(*child.spawn_key, key)))


def world_seed(seed: int, name: str) -> int:
    """An integer seed for a world of its own (the worlds take an int), drawn from stream
    `name` of run `seed`: e.g. the teacher's world, "teacher-world" (core/teaching.py)."""
    return int(component_rng(seed, name).integers(2**31 - 1))


@dataclass
class RandomStreams:
    """The learner's generators: goal choice, exploration, imitation noise, random actions."""

    goals: np.random.Generator
    explorer: np.random.Generator
    imitation: np.random.Generator
    random: np.random.Generator

    @classmethod
    def from_seed(cls, seed: int) -> RandomStreams:
        return cls(
            *(component_rng(seed, name) for name in ("goals", "explorer", "imitation", "random"))
        )
