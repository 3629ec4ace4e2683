"""Casts of uniformly random actions, with no learner: how the world itself behaves.

The isolated region's rarity (docs/isolated_region.md) is the share of random actions whose
cast comes down in the pond. Casts are made in chunks, each with its own seed, written whole to
one file: a runs folder resumes by skipping the chunks already made, and two processes make
two chunks side by side.

    runs:
      casts: 50000      # in all
      chunk: 5000       # per file
      seed: 1           # chunk k draws its actions from default_rng([seed, k])
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sgim_nodes.provenance import fingerprint as fp

KEYS = ("casts", "chunk", "seed")


@dataclass(frozen=True)
class CastChunk:
    seed: int
    index: int
    casts: int

    @property
    def name(self) -> str:
        return f"casts-seed{self.seed}-chunk{self.index}"

    def fingerprint(self) -> fp.Fingerprint:
        return fp.fingerprint({"maker": "world", "seed": self.seed, "chunk": self.index,
                               "casts": self.casts})


def expand_jobs(runs: Mapping[str, Any], where: str) -> list[CastChunk]:
    unknown = sorted(set(runs) - set(KEYS))
    values = {k: runs.get(k) for k in KEYS}
    if unknown or not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0
                          for v in values.values()) or values["chunk"] < 1:
        raise ValueError(f"{where}: runs takes casts, chunk (>= 1) and seed, integers")
    total, chunk = values["casts"], values["chunk"]
    return [CastChunk(values["seed"], k, min(chunk, total - k * chunk))
            for k in range(math.ceil(total / chunk))]


def touch_downs(job: CastChunk) -> np.ndarray:
    """World points (casts, 2) in metres where each cast came down, on water or on land;
    NaN rows for a cast that never came down."""
    from sim_bridge.fishing_world import FishingWorld

    rng = np.random.default_rng([job.seed, job.index])
    out = np.full((job.casts, 2), np.nan)
    with FishingWorld(seed=job.seed * 1000 + job.index) as world:
        for i, action in enumerate(rng.uniform(-1.0, 1.0, (job.casts, world.action_dim))):
            result = world.execute(action)
            if result.world_point is not None:
                out[i] = result.world_point
    return out


def run_job(job: CastChunk) -> dict[str, Any]:
    import time

    start = time.perf_counter()
    points = touch_downs(job)
    return {"name": job.name, "points": points, "fingerprint": job.fingerprint().value,
            "seconds": time.perf_counter() - start}


def result_path(runs_dir: Path, job: CastChunk) -> Path:
    return runs_dir / f"{job.name}.npz"


def write_result(path: Path, result: dict[str, Any]) -> None:
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.npz")
    np.savez_compressed(tmp, points=result["points"], fingerprint=result["fingerprint"],
                        seconds=result["seconds"])
    tmp.replace(path)


def read_result(path: Path) -> dict[str, Any] | None:
    try:
        with np.load(path, allow_pickle=False) as data:
            return {"points": data["points"], "fingerprint": str(data["fingerprint"]),
                    "seconds": float(data["seconds"])}
    except (OSError, KeyError, ValueError):
        return None


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial share k / n (the counts are small)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)
