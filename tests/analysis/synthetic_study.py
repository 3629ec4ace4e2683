"""A tiny synthetic study written as real bags (rosbags, no ROS) with numbers known by hand.

Layout as run_study.sh writes it: <study>/<learner>-seed<N>/bag/ and metadata.yaml.
Each run has 20 movements, evaluations at 0, 10 and 20, and (for tree learners) region maps.
Every run's metadata carries a learner fingerprint, by default one shared by all (FINGERPRINT);
fingerprint(**fields) makes another, and write_run(..., fingerprint=None) a run made before
fingerprints. acts_records and demonstrations_at add what an SGIM-ACTS run records (its
requests, the experts' answers, the episodes' strategies) and an SGIM-D run's demonstrations.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from sgim_nodes.provenance.fingerprint import Fingerprint, canonical
from sim_bridge.lake import ISOLATED_REGION, Lake
from tests.bag.samples import T, region, stamp, write_bag

N_MOVES = 20
EVAL_POINTS = (0, 10, 20)
INSIDE = tuple(ISOLATED_REGION["centre"])  # the isolated region's centre
OUTSIDE = (0.3, 0.1)

# Final errors (evaluation at 20) per learner and seed, and the earlier points.
FINALS = {"sgim-d": [0.20, 0.25, 0.30], "random": [0.50, 0.55, 0.65]}
AT_10 = {"sgim-d": [0.40, 0.44, 0.42], "random": [0.60, 0.61, 0.62]}
AT_0 = 0.9

FIELDS = {"code": "c0de0000c0de0000", "world": "3071d000", "data": "da7a0000", "numpy": "2.4.6",
          "scipy": "1.17.1", "pybullet": "3.2.7", "python": "3.11.7",
          "parameters": "9a7a0000"}
PARAMETERS = {"learner": {"demonstration_period": 150, "imitations": 5}}


def fingerprint(parameters: dict[str, Any] | None = None, **fields: str) -> dict[str, Any]:
    """A fingerprint's metadata mapping: the shared one, with these fields (and, given
    ``parameters``, these parameters and a digest of them) changed."""
    params = PARAMETERS if parameters is None else parameters
    changed = dict(FIELDS, **fields)
    if parameters is not None and "parameters" not in fields:
        changed["parameters"] = hashlib.sha256(canonical(params).encode()).hexdigest()[:16]
    return Fingerprint(changed, params).to_dict()


FINGERPRINT = fingerprint()


def movement(index: int, outcome, process: int = 0, status: int = 0):
    kind = T["sgim_msgs/msg/Movement"]
    unsigned = ({"signature": np.zeros(0, dtype=np.uint8)}  # a run made without a key
                if "signature" in getattr(kind, "__dataclass_fields__", {}) else {})
    return kind(
        stamp=stamp(index), index=index, process=process, status=status,
        action=np.zeros(24), outcome=np.zeros(0) if outcome is None else np.asarray(outcome),
        goal=np.zeros(2), goal_index=0, attempt=0, **unsigned)


def evaluation(index: int, mean: float):
    distances = np.array([mean - 0.1, mean + 0.1])
    return T["sgim_msgs/msg/Evaluation"](
        stamp=stamp(index), movement_index=index, mean_distance=mean, outcome_size=2,
        goals=np.zeros(4), reached=np.zeros(4), distances=distances)


def region_map(index: int, split: bool):
    regions = [region(0, -1, [-1, -1], [1, 1], not split)]
    if split:
        regions += [region(1, 0, [-1, -1], [0, 1], True), region(2, 0, [0, -1], [1, 1], True)]
    return T["sgim_msgs/msg/RegionMap"](stamp=stamp(index), movement_index=index,
                                        split_count=int(split), goal_count=index,
                                        regions=regions)


def run_status(learner: str, seed: int, index: int, state: int, total: int = N_MOVES):
    return T["sgim_msgs/msg/RunStatus"](stamp=stamp(index), learner=learner, seed=seed,
                                        movement_index=index, total_movements=total,
                                        state=state, message="")


def run_messages(learner: str, seed: int, evals: dict[int, float],
                 inside: dict[int, int] | None = None, failed: tuple[int, ...] = (7,),
                 maps: bool = False, extra: dict[int, list] | None = None
                 ) -> list[tuple[str, object]]:
    """Movements 1..20 landing OUTSIDE except `inside` (index -> process) and `failed`;
    `extra`: records published at a movement count, before the next movement."""
    inside, extra = inside or {}, extra or {}
    out: list[tuple[str, object]] = [("run_status", run_status(learner, seed, 0, 0))]
    if 0 in evals:
        out.append(("evaluations", evaluation(0, evals[0])))
    for i in range(1, N_MOVES + 1):
        out += extra.get(i - 1, [])
        if i in failed:
            out.append(("movements", movement(i, None, status=1)))
        else:
            out.append(("movements", movement(i, INSIDE if i in inside else OUTSIDE,
                                              process=inside.get(i, 0))))
        if maps and i % 10 == 0:
            out.append(("region_map", region_map(i, split=i >= 20)))
        if i in evals:
            out.append(("evaluations", evaluation(i, evals[i])))
    out.append(("run_status", run_status(learner, seed, N_MOVES, 1)))
    return out


def write_run(study: Path, learner: str, seed: int, messages: list[tuple[str, object]],
              duration_s: float = 10.0, fingerprint: dict[str, Any] | None = FINGERPRINT,
              name: str | None = None, parameters: dict[str, Any] | None = None,
              **writer_kwargs) -> Path:
    """One run folder (``name``: its folder, else <learner>-seed<N>); ``fingerprint=None``: a
    run made before fingerprints; ``parameters``: its metadata's."""
    run_dir = study / (name or f"{learner}-seed{seed}")
    run_dir.mkdir(parents=True)
    write_bag(run_dir / "bag", messages, **writer_kwargs)
    meta = {"learner": learner, "seed": seed, "movements": N_MOVES, "outcome": "finished",
            "duration_s": duration_s}
    if parameters is not None:
        meta["parameters"] = parameters
    if fingerprint is not None:
        meta["fingerprint"] = fingerprint
    (run_dir / "metadata.yaml").write_text(yaml.safe_dump(meta))
    return run_dir


def write_study(study: Path, seeds: int = 3, learners: tuple[str, ...] = ("sgim-d", "random"),
                fingerprints: dict[str, dict[str, Any] | None] | None = None) -> Path:
    """sgim-d seed 0 lands in the isolated region at 5 and 12 (own) and 9 (imitation).
    ``fingerprints``: run name -> its fingerprint (None: none), FINGERPRINT for the others."""
    fingerprints = fingerprints or {}
    for learner in learners:
        for seed in range(seeds):
            evals = {0: AT_0, 10: AT_10[learner][seed], 20: FINALS[learner][seed]}
            inside = {5: 0, 9: 2, 12: 1} if (learner, seed) == ("sgim-d", 0) else {}
            write_run(study, learner, seed,
                      run_messages(learner, seed, evals, inside, maps=learner == "sgim-d"),
                      duration_s=10.0 + seed,
                      fingerprint=fingerprints.get(f"{learner}-seed{seed}", FINGERPRINT))
    return study


def part_points() -> dict[str, tuple[float, float]]:
    """A goal (normalised outcome units) in each named part of the lake and on land: the first
    point of a regular grid that lies there."""
    lake, found = Lake(), {}
    for x in np.linspace(-0.95, 0.95, 39):
        for y in np.linspace(-0.95, 0.95, 39):
            found.setdefault(lake.part_of_outcome((x, y)), (float(x), float(y)))
    return found


ACTS_EPISODES = [
    (0, "autonomous", "basin", True),
    (2, "mimicry:centre", "basin", True),
    (4, "emulation:rough", "west", False),
    (6, "autonomous", "basin", True),
    (10, "mimicry:centre", "north", False),
    (12, "emulation:west", "pond", True),
    (14, "mimicry:rough", "basin", False),
    (15, "mimicry:centre", "basin", False),
    (16, "autonomous", "east", True),
    (18, "mimicry:west", "land", False),
]
"""An SGIM-ACTS run of 20 movements: 7 requests, 2 answers that showed what was asked for
(taken); in the last 10 movements 5 requests, 4 about a part one precise expert knows (north
and basin: centre's, the pond: west's), 3 of them sent to it, and 1 to rough. Per window of 10
movements: 4 episodes then 6, autonomous 2 of the first 4."""


def acts_records(episodes: list[tuple[int, str, str, bool]]) -> dict[int, list]:
    """An SGIM-ACTS run's records for ``episodes`` (movement count when chosen, strategy, part
    of the world its goal lies in, answered): the Goal naming the strategy; for a social one,
    the request to its teacher, the answer (empty: "none there") and, when answered, the
    demonstration taken; by movement count, for run_messages' ``extra``."""
    points, out = part_points(), {}
    requests = 0
    for k, (count, strategy, part, answered) in enumerate(episodes, 1):
        point = np.asarray(points[part])
        records = out.setdefault(count, [])
        records.append(("goals", T["sgim_msgs/msg/Goal"](
            stamp=stamp(count), index=k, movement_index=count, point=point, region_id=0,
            mode=1, strategy=strategy)))
        kind, _, teacher = strategy.partition(":")
        if not teacher:
            continue
        requests += 1
        content = "means-and-goal" if kind == "mimicry" else "goal-only"
        records.append(("help_requests", T["sgim_msgs/msg/HelpRequest"](
            stamp=stamp(count), index=requests, movement_index=count, goal=point,
            teacher=teacher, content=content, signature=np.zeros(0, dtype=np.uint8))))
        shown = answered and kind == "mimicry"
        answer = T["sgim_msgs/msg/Demonstration"](
            stamp=stamp(count), index=requests, movement_index=count,
            action=np.zeros(24) if shown else np.zeros(0),
            outcome=point if answered else np.zeros(0), teaching_set_index=0,
            source=f"expert:{teacher}", content=content, help_request=requests,
            signature=np.zeros(0, dtype=np.uint8))
        records.append(("demonstrations", answer))
        if answered:
            records.append(("demonstrations_taken", answer))
    return out


def demonstrations_at(counts: list[int]) -> dict[int, list]:
    """A periodic teacher's demonstrations, one shown and taken at each movement count."""
    out: dict[int, list] = {}
    for k, count in enumerate(counts, 1):
        demo = T["sgim_msgs/msg/Demonstration"](
            stamp=stamp(count), index=k, movement_index=count, action=np.zeros(24),
            outcome=np.asarray(OUTSIDE), teaching_set_index=k, source="automatic",
            content="means-and-goal", help_request=0, signature=np.zeros(0, dtype=np.uint8))
        out[count] = [("demonstrations", demo), ("demonstrations_taken", demo)]
    return out
