"""The isolated region's rarity: the share of random actions whose cast comes down in it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sgim_nodes.experiments import shipped, world_jobs
from sgim_nodes.experiments.pinned import Experiment
from sgim_nodes.experiments.reports import Report

RUN_LENGTH = 5000  # movements of a random run, for the expected hits and the chance to miss


def make(experiment: Experiment, runs_dir: Path, figures_dir: Path) -> Report:
    from sim_bridge.lake import DEFAULT_LAKE, ISOLATED_POND, POND

    chunks = []
    for job in experiment.world_jobs:
        if not isinstance(job, world_jobs.CastChunk):
            continue  # a probe of the physics: the world report's
        found = shipped.read_result(experiment, runs_dir, job)
        if found is None:
            raise FileNotFoundError(f"{job.name} is not made yet: run the experiment first")
        chunks.append(found)
    points = np.concatenate([c["points"] for c in chunks])
    seconds = sum(c["seconds"] for c in chunks)
    down = np.isfinite(points[:, 0])
    n = len(points)
    hits = int(np.sum(DEFAULT_LAKE.water_body(points[down]) == ISOLATED_POND))
    water = int(np.sum(DEFAULT_LAKE.water_body(points[down]) > 0))
    low, high = world_jobs.wilson(hits, n)
    expected = RUN_LENGTH * hits / n
    region = DEFAULT_LAKE.isolated_region()
    report = Report()
    page = experiment.pages[0]
    table = [
        "| what | figure |", "|---|---|",
        f"| random casts | {n:,} ({int(down.sum()):,} came down, {water:,} on water: "
        f"{100 * water / n:.1f} %) |",
        f"| the isolated region | centre ({POND[0]}, {POND[1]}) m, radius {POND[2]} m "
        f"(normalised: centre ({region['centre'][0]:.2f}, {region['centre'][1]:.2f}), "
        f"radius {region['radius']:.3f}) |",
        f"| casts landing in it | **{hits}**: **{100 * hits / n:.3f} %** of random actions "
        f"(95 % Wilson interval {100 * low:.3f}-{100 * high:.3f} %) |",
        f"| in a random run of {RUN_LENGTH} movements | {expected:.2f} landings on average; "
        f"no landing at all with probability {math.exp(-expected):.2f} (Poisson) |",
        f"| casting time | {seconds / 60:.1f} min of CPU ({n / seconds:.1f} casts/s) |",
    ]
    report.add(page, "pond-share", "\n".join(table))
    report.add(page, "pond-data", pond_data())
    return report


def pond_data() -> str:
    """What the world's data files hold of the pond: its teaching entries, its benchmark
    goals and their floor, the map's landings there."""
    from sim_bridge.data_files import (
        in_isolated_region,
        load_benchmark_goals,
        load_floor,
        load_reachable_map,
        load_teaching_set,
    )

    teaching = load_teaching_set()
    entries = np.flatnonzero(in_isolated_region(teaching.outcomes))
    goals = np.asarray(load_benchmark_goals(), float)
    inside = in_isolated_region(goals)
    floor = np.asarray(load_floor().per_goal, float).ravel()
    mapped = np.asarray(load_reachable_map(), float)
    shown = "; ".join(f"entry {k} of {len(teaching.outcomes)}, mean outcome "
                      f"({teaching.outcomes[k][0]:.3f}, {teaching.outcomes[k][1]:.3f}), "
                      f"spread {teaching.spread[k]:.3f}" for k in entries) or "none"
    rows = ["| what | figure |", "|---|---|",
            f"| teaching set (`teaching_set.npz`) | {shown} |",
            f"| benchmark goals in it (`benchmark_goals.npz`) | {int(inside.sum())} of "
            f"{len(goals)} |",
            f"| the floor on those goals (`benchmark_floor.npz`) | "
            f"{floor[inside].mean():.3f}, against {floor[~inside].mean():.3f} on the others |"
            if inside.any() else "| the floor on those goals | no goal in it |",
            f"| landings in it of the dense map (`reachable_map.npz`) | "
            f"{int(in_isolated_region(mapped).sum())} of {len(mapped)} |"]
    return "\n".join(rows)
