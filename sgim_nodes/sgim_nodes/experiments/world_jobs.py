"""The world itself, with no learner: casts of uniformly random actions, and probes of its
physics (experiments/world_probes.py).

The isolated region's rarity (docs/isolated_region.md) is the share of random actions whose
cast comes down in the pond. Casts are made in chunks, each with its own seed, written whole to
one file: a runs folder resumes by skipping the chunks already made, and two processes make
two chunks side by side. A probe is a job too, one per seed.

    runs:
      casts: 50000      # in all
      chunk: 5000       # per file
      seed: 1           # chunk k draws its actions from default_rng([seed, k])
      # and any of the probes, each {seeds: N (0..N-1) or [..], actions: N}, noise also
      # {attempts: N}:
      sensitivity: {seeds: 1, actions: 20}
      time_step: {seeds: 1, actions: 100}
      noise: {seeds: 12, actions: 20, attempts: 10}
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
PROBE_KEYS = {"sensitivity": ("seeds", "actions"), "time_step": ("seeds", "actions"),
              "noise": ("seeds", "actions", "attempts")}


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


@dataclass(frozen=True)
class Probe:
    """One seed's probe of the world's physics (world_probes.PROBES names them)."""

    kind: str
    seed: int
    actions: int
    attempts: int = 0  # the noise probe's casts per action

    @property
    def name(self) -> str:
        return f"{self.kind}-seed{self.seed}"

    def fingerprint(self) -> fp.Fingerprint:
        """Its settings and the probes' code: another way of measuring is another result."""
        from sgim_nodes.experiments import world_probes

        return fp.fingerprint({"maker": "world", "probe": self.kind, "seed": self.seed,
                               "actions": self.actions, "attempts": self.attempts,
                               "probe_code": fp.source_digest([Path(world_probes.__file__)])})


def _count(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def expand_jobs(runs: Mapping[str, Any], where: str) -> list[CastChunk | Probe]:
    unknown = sorted(set(runs) - set(KEYS) - set(PROBE_KEYS))
    if unknown:
        raise ValueError(f"{where}: runs has no {', '.join(unknown)} (it takes "
                         f"{', '.join((*KEYS, *PROBE_KEYS))})")
    jobs: list[CastChunk | Probe] = []
    if any(k in runs for k in KEYS):
        values = {k: runs.get(k) for k in KEYS}
        if not all(_count(v) for v in values.values()) or values["chunk"] < 1:
            raise ValueError(f"{where}: runs takes casts, chunk (>= 1) and seed, integers")
        total, chunk = values["casts"], values["chunk"]
        jobs += [CastChunk(values["seed"], k, min(chunk, total - k * chunk))
                 for k in range(math.ceil(total / chunk))]
    for kind, keys in PROBE_KEYS.items():
        if kind not in runs:
            continue
        spec = runs[kind]
        seeds = spec.get("seeds") if isinstance(spec, Mapping) else None
        seeds = list(range(seeds)) if _count(seeds) else seeds
        if (not isinstance(spec, Mapping) or sorted(spec) != sorted(keys)
                or not isinstance(seeds, list) or not seeds or not all(map(_count, seeds))
                or not all(_count(spec[k]) and spec[k] >= 1 for k in keys if k != "seeds")):
            raise ValueError(f"{where}: runs: {kind} takes {', '.join(keys)}: positive "
                             "integers (seeds: a count or a list of seeds)")
        jobs += [Probe(kind, seed, spec["actions"], spec.get("attempts", 0)) for seed in seeds]
    if not jobs:
        raise ValueError(f"{where}: runs names no casts and no probe")
    return jobs


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


def run_job(job: CastChunk | Probe) -> dict[str, Any]:
    """A chunk's touch-down points ("points"), or a probe's figures ("values")."""
    import time

    start = time.perf_counter()
    if isinstance(job, Probe):
        from sgim_nodes.experiments.world_probes import PROBES

        extra = (job.attempts,) if job.kind == "noise" else ()
        made = {"values": PROBES[job.kind](job.seed, job.actions, *extra)}
    else:
        made = {"points": touch_downs(job)}
    return {"name": job.name, **made, "fingerprint": job.fingerprint().value,
            "seconds": time.perf_counter() - start}


def result_path(runs_dir: Path, job: CastChunk | Probe) -> Path:
    return runs_dir / f"{job.name}.npz"


def write_result(path: Path, result: dict[str, Any]) -> None:
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.npz")
    arrays = {k: result[k] for k in ("points", "values") if k in result}
    np.savez_compressed(tmp, **arrays, fingerprint=result["fingerprint"],
                        seconds=result["seconds"])
    tmp.replace(path)


def read_result(path: Path) -> dict[str, Any] | None:
    """The result file's arrays ("points" or "values"), fingerprint and seconds; None if it
    cannot be read."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in ("points", "values") if k in data.files}
            if not arrays:
                return None
            return {**arrays, "fingerprint": str(data["fingerprint"]),
                    "seconds": float(data["seconds"])}
    except (OSError, KeyError, ValueError):
        return None


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial share k / n (the counts are small)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)
