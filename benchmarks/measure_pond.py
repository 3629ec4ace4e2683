"""How rarely random actions reach the isolated region, and how learners' runs covered it.

Random actions (the default): cast ``--casts`` uniformly random actions in the default world,
keep every touch-down (on water or land), and print the share that lands in the isolated region
with its 95 % interval (Wilson's: the counts are small), the expected number of hits in a run of
``--movements`` random movements and the chance that such a run never hits it. ``--radii R ...``
(metres) adds one row per pond radius at the region's centre: the lake only decides whether a
touch-down is water or land, never the physics, so one batch of casts serves every radius.
``--save`` keeps the touch-downs; ``--load`` merges saved batches (e.g. two seeds run one after
the other) without casting again.

Runs (``--runs PATH ...``, no casting): each PATH is a JSON-lines file of the single-process
runner (``python -m sgim_nodes.core.runner ... --output F.jsonl``), a run folder of the graph
(``<learner>-seed<N>/`` with ``bag/``) or a study folder holding run folders. Per run: the
learner's own movements whose outcome lies in the isolated region (imitations and
demonstrations not counted), the first of them, the own outcome closest to the region's centre,
the movements at which the teacher showed an entry in the region, and the final error. Per
learner: runs reaching the region, own landings per run; between learners: Fisher's exact test
on "runs reaching it" and Mann-Whitney U on own landings per run. ``--pond-radius`` sets the
region of runs made with a smaller pond (runner files record it themselves).

    PYTHONPATH=sim_bridge .venv/bin/python benchmarks/measure_pond.py --casts 100000 --seed 1
    PYTHONPATH=sgim_nodes:sim_bridge .venv/bin/python benchmarks/measure_pond.py --runs runs/*
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import dataclass, field
from itertools import combinations
from pathlib import Path

import numpy as np
from tqdm import tqdm

from sim_bridge.fishing_world import FishingWorld
from sim_bridge.lake import DEFAULT_LAKE, ISOLATED_POND, POND, Lake

OWN_LABELS = ("goal_directed", "exploration", "random")  # not imitation, not demonstration


def touch_downs(n: int, seed: int, progress: bool = True) -> np.ndarray:
    """World points (n, 2) in metres where random casts came down; NaN rows if never down."""
    rng = np.random.default_rng(seed)
    out = np.full((n, 2), np.nan)
    with FishingWorld(seed=seed) as w:
        for i, a in enumerate(tqdm(rng.uniform(-1, 1, (n, w.action_dim)), desc="casts",
                                   disable=not progress)):
            r = w.execute(a)
            if r.world_point is not None:
                out[i] = r.world_point
    return out


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial share k / n."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def table(points: np.ndarray, radii: list[float], movements: int) -> str:
    """One row per radius: hits, share with its interval, expected hits and the chance that a
    random run of ``movements`` movements never reaches the region (Poisson, from the share)."""
    n = len(points)
    down = np.isfinite(points[:, 0])
    rows = [f"{n} random casts ({int(down.sum())} came down); isolated region centred at "
            f"({POND[0]}, {POND[1]}) m",
            f"{'radius m':>9} {'norm.':>6} {'hits':>5} {'share %':>8} {'95% interval %':>16} "
            f"{'hits/' + str(movements):>10} {'P(miss)':>8}"]
    for r in radii:
        lake = Lake(pond_radius=r)
        k = int(np.sum(lake.water_body(points[down]) == ISOLATED_POND))
        lo, hi = wilson(k, n)
        rad_n = lake.isolated_region()["radius"]
        mark = "  <- default world" if lake.is_default else ""
        rows.append(f"{r:9.4f} {rad_n:6.4f} {k:5d} {100 * k / n:8.3f} "
                    f"{100 * lo:7.3f} - {100 * hi:6.3f} {movements * k / n:10.2f} "
                    f"{math.exp(-movements * k / n):8.3f}{mark}")
    return "\n".join(rows)


@dataclass
class Run:
    """What a run says about the isolated region, whatever file it came from."""

    learner: str
    seed: int
    movement: np.ndarray  # (N,) movement index of each own movement with an outcome
    outcome: np.ndarray  # (N, 2)
    label: list[str]
    demos: list[tuple[int, np.ndarray]] = field(default_factory=list)
    movements: int = 0
    final: float = math.nan
    pond_radius: float | None = None


def read_jsonl(path: Path) -> Run:
    """A runner JSON-lines file: header, movement, demonstration, evaluation and end records."""
    header, end, own, demos, last_eval = {}, {}, [], [], None
    with path.open() as f:
        for line in f:
            r = json.loads(line)
            kind = r.get("type")
            if kind == "header":
                header = r
            elif kind == "end":
                end = r
            elif kind == "movement" and r.get("outcome") is not None:
                if r.get("label", "goal_directed") in OWN_LABELS:
                    own.append((r["index"], r["outcome"], r.get("label", "?")))
            elif kind == "demonstration":
                demos.append((r.get("movement", -1), np.asarray(r["outcome"], dtype=float)))
            elif kind == "evaluation":
                last_eval = r
    return Run(learner=str(header.get("learner", path.stem)), seed=int(header.get("seed", -1)),
               movement=np.array([i for i, _, _ in own], dtype=int),
               outcome=np.array([o for _, o, _ in own], dtype=float).reshape(-1, 2),
               label=[lab for _, _, lab in own], demos=demos,
               movements=int(last_eval["movements"]) if last_eval else 0,
               final=float(end.get("final_mean_distance",
                                   last_eval["mean_distance"] if last_eval else math.nan)),
               pond_radius=header.get("pond_radius"))


def read_run_folders(path: Path) -> list[Run]:
    """Run folders of the graph (or a study folder of them), read by the analysis package."""
    from sgim_nodes.analysis.study import (
        PROCESS_DEMONSTRATION,
        PROCESS_IMITATION,
        STATUS_OK,
        discover_runs,
        load_run_data,
    )
    from sgim_nodes.core.environment import PROCESS_LABELS

    runs = []
    for folder in discover_runs(path):
        d = load_run_data(folder)
        if d is None:
            continue
        own = ((d.status == STATUS_OK) & np.isfinite(d.outcome).all(axis=1)
               & ~np.isin(d.process, [PROCESS_IMITATION, PROCESS_DEMONSTRATION]))
        runs.append(Run(learner=d.learner, seed=d.seed, movement=d.movement_index[own],
                        outcome=d.outcome[own],
                        label=[PROCESS_LABELS.get(int(p), "?") for p in d.process[own]],
                        demos=list(zip(d.demo_index.tolist(), d.demo_outcome, strict=True)),
                        movements=d.movements_done,
                        final=float(d.eval_mean[-1]) if len(d.eval_mean) else math.nan,
                        pond_radius=d.metadata.get("pond_radius")))
    return runs


def read_runs(paths: list[Path]) -> list[Run]:
    runs: list[Run] = []
    for p in paths:
        runs += read_run_folders(p) if p.is_dir() else [read_jsonl(p)]
    return runs


def run_row(run: Run, lake: Lake) -> dict[str, object]:
    if run.pond_radius is not None and lake.is_default:
        lake = Lake(pond_radius=float(run.pond_radius))
    centre = np.array(lake.isolated_region()["centre"])
    inside = lake.in_isolated_region(run.outcome)
    dist = np.linalg.norm(run.outcome - centre, axis=1)
    return {"learner": run.learner, "seed": run.seed, "movements": run.movements,
            "in_region": int(inside.sum()),
            "first": int(run.movement[inside].min()) if inside.any() else None,
            "closest": float(dist.min()) if len(dist) else math.nan,
            "labels": ",".join(sorted({run.label[i] for i in np.flatnonzero(inside)})) or "-",
            "demos": [m for m, o in run.demos if lake.in_isolated_region(o)],
            "final": run.final}


def runs_report(runs: list[Run], lake: Lake = DEFAULT_LAKE) -> str:
    from scipy.stats import fisher_exact, mannwhitneyu

    rows = [run_row(r, lake) for r in sorted(runs, key=lambda r: (r.learner, r.seed))]
    out = [f"isolated region {lake.isolated_region()} (normalised units)",
           f"{'learner':<11} {'seed':>4} {'moves':>5} {'own in':>6} {'first':>6} "
           f"{'closest':>8} {'final err':>9}  region demos at / own landings by"]
    for s in rows:
        first = "-" if s["first"] is None else str(s["first"])
        out.append(f"{s['learner']:<11} {s['seed']:>4} {s['movements']:>5} "
                   f"{s['in_region']:>6} {first:>6} {s['closest']:8.4f} {s['final']:9.4f}  "
                   f"{s['demos'] or '-'} / {s['labels']}")
    by: dict[str, list[dict]] = {}
    for s in rows:
        by.setdefault(str(s["learner"]), []).append(s)
    out += ["", f"{'learner':<11} {'runs reaching':>13} {'own landings per run':<30}"]
    for learner, rs in by.items():
        reached = sum(r["in_region"] > 0 for r in rs)
        out.append(f"{learner:<11} {f'{reached}/{len(rs)}':>13} "
                   f"{', '.join(str(r['in_region']) for r in rs):<30}")
    if len(by) > 1:
        out += ["", "pairwise: Fisher's exact test on runs reaching it, Mann-Whitney U on own "
                    "landings per run (two-sided)"]
        for a, b in combinations(by, 2):
            ra, rb = by[a], by[b]
            ka, kb = (sum(r["in_region"] > 0 for r in x) for x in (ra, rb))
            p_f = fisher_exact([[ka, len(ra) - ka], [kb, len(rb) - kb]]).pvalue
            ca, cb = ([r["in_region"] for r in x] for x in (ra, rb))
            p_u = (mannwhitneyu(ca, cb).pvalue if len(set(ca + cb)) > 1 else 1.0)
            out.append(f"  {a} vs {b}: Fisher p = {p_f:.3g}, Mann-Whitney p = {p_u:.3g}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--casts", type=int, default=100_000,
                        help="random casts (0 with --load)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the actions and the noise")
    parser.add_argument("--radii", type=float, nargs="+", default=[POND[2]],
                        help="pond radii in metres (default: the default world's)")
    parser.add_argument("--movements", type=int, default=5000,
                        help="run length for the expected hits and P(miss) columns")
    parser.add_argument("--save", default=None, help="save the touch-downs (.npy)")
    parser.add_argument("--load", nargs="*", default=[], help="touch-down files to merge")
    parser.add_argument("--runs", nargs="*", type=Path, default=[],
                        help="runner JSON-lines files, run folders or study folders")
    parser.add_argument("--pond-radius", type=float, default=None,
                        help="with --runs: the region of runs made with another pond radius")
    args = parser.parse_args(argv)
    if args.runs:
        lake = DEFAULT_LAKE if args.pond_radius is None else Lake(pond_radius=args.pond_radius)
        runs = read_runs(args.runs)
        if not runs:
            parser.error("no readable run among --runs")
        print(runs_report(runs, lake))
        return
    if args.casts < 0 or any(r <= 0 for r in args.radii):
        parser.error("--casts must be >= 0 and --radii positive")
    parts = [np.load(f) for f in args.load]
    if args.casts > 0:
        t0 = time.perf_counter()
        pts = touch_downs(args.casts, args.seed)
        print(f"{args.casts} casts in {time.perf_counter() - t0:.0f} s (seed {args.seed})")
        if args.save:
            np.save(args.save, pts)
        parts.append(pts)
    if not parts:
        parser.error("nothing to measure: give --casts > 0 or --load")
    print(table(np.concatenate(parts), args.radii, args.movements))


if __name__ == "__main__":
    main()
