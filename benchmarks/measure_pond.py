"""Share of uniformly random actions that land in the isolated pond, for several pond radii.

Why one batch of casts serves every radius: the lake (``lake.Lake``) only decides whether a
touch-down point is water or land; the physics, the noise and the touch-down point itself do not
depend on it. So the script casts ``--casts`` random actions once in the default world, keeps
every touch-down point (on water or on land) and classifies them with each radius's lake
(``Lake(pond_radius=r).water_body``): a cast reaches a pond of radius r exactly when its
touch-down lies in that disc. The 95 % interval is Wilson's (binomial counts are small).
``--save`` keeps the touch-downs, ``--load`` merges saved batches (e.g. two seeds run side by
side on two cores) without casting again.

``--runs F.jsonl ...`` (no casting) summarises runs of the single-process runner instead
(``python -m sgim_nodes.core.runner --env fishing --pond-radius R ...``): per run, the learner's
own movements that landed in the pond, the first of them, the closest own outcome to the pond's
centre, the movements at which the teacher showed a pond entry, and the final mean error.

    PYTHONPATH=sim_bridge .venv/bin/python benchmarks/measure_pond.py --casts 20000 --seed 1
    PYTHONPATH=sim_bridge .venv/bin/python benchmarks/measure_pond.py --runs runs/*.jsonl
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from sim_bridge.fishing_world import FishingWorld
from sim_bridge.lake import ISOLATED_POND, POND, Lake

DEFAULT_RADII = (POND[2], POND[2] / 2, POND[2] / 3, POND[2] / 4, POND[2] / 5)


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
    random run of ``movements`` movements never reaches the pond (Poisson, from the share)."""
    n = len(points)
    down = np.isfinite(points[:, 0])
    rows = [f"{n} random casts ({int(down.sum())} came down)",
            f"{'radius m':>9} {'norm.':>6} {'hits':>5} {'share %':>8} {'95% interval %':>16} "
            f"{'hits/' + str(movements):>10} {'P(miss)':>8}"]
    for r in radii:
        lake = Lake(pond_radius=r)
        k = int(np.sum(lake.water_body(points[down]) == ISOLATED_POND))
        lo, hi = wilson(k, n)
        rad_n = lake.isolated_region()["radius"]
        rows.append(f"{r:9.4f} {rad_n:6.4f} {k:5d} {100 * k / n:8.3f} "
                    f"{100 * lo:7.3f} - {100 * hi:6.3f} {movements * k / n:10.2f} "
                    f"{math.exp(-movements * k / n):8.3f}")
    return "\n".join(rows)


def summarise_run(path: Path) -> dict[str, object]:
    """Pond coverage and final error of one runner JSON-lines file."""
    header, end, own, demos, last_eval = {}, {}, [], [], None
    with path.open() as f:
        for line in f:
            r = json.loads(line)
            if r["type"] == "header":
                header = r
            elif r["type"] == "end":
                end = r
            elif r["type"] == "movement" and r["outcome"] is not None:
                own.append((r["index"], r["outcome"], r["label"]))
            elif r["type"] == "demonstration":
                demos.append((r["movement"], r["outcome"]))
            elif r["type"] == "evaluation":
                last_eval = r
    lake = Lake(pond_radius=header.get("pond_radius") or POND[2])
    centre = np.array(lake.isolated_region()["centre"])
    idx = np.array([i for i, _, _ in own], dtype=int)
    out = np.array([o for _, o, _ in own], dtype=float).reshape(-1, 2)
    in_pond = lake.in_isolated_region(out)
    labels = sorted({own[i][2] for i in np.flatnonzero(in_pond)})
    pond_demos = [m for m, o in demos if lake.in_isolated_region(np.array(o))]
    dist = np.linalg.norm(out - centre, axis=1)
    return {"learner": header.get("learner"), "seed": header.get("seed"),
            "movements": int(last_eval["movements"]) if last_eval else 0,
            "pond": int(in_pond.sum()),
            "first": int(idx[in_pond][0]) if in_pond.any() else None,
            "labels": ",".join(labels) or "-",
            "closest": float(dist.min()) if len(dist) else math.nan,
            "pond_demos": pond_demos,
            "final": end.get("final_mean_distance",
                             last_eval["mean_distance"] if last_eval else math.nan)}


def runs_table(paths: list[Path]) -> str:
    rows = [f"{'learner':<9} {'seed':>4} {'moves':>5} {'pond':>5} {'first':>6} "
            f"{'closest':>8} {'final err':>9}  pond demos at / pond landings by"]
    for p in sorted(paths):
        s = summarise_run(p)
        first = "-" if s["first"] is None else str(s["first"])
        rows.append(f"{s['learner']:<9} {s['seed']:>4} {s['movements']:>5} {s['pond']:>5} "
                    f"{first:>6} {s['closest']:8.4f} {s['final']:9.4f}  "
                    f"{s['pond_demos'] or '-'} / {s['labels']}")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--casts", type=int, default=20000, help="random casts (0 with --load)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the actions and the noise")
    parser.add_argument("--radii", type=float, nargs="+", default=list(DEFAULT_RADII),
                        help="pond radii in metres (default: 1, 1/2, 1/3, 1/4, 1/5 of 0.95)")
    parser.add_argument("--movements", type=int, default=5000,
                        help="run length for the expected hits and P(miss) columns")
    parser.add_argument("--save", default=None, help="save the touch-downs (.npy)")
    parser.add_argument("--load", nargs="*", default=[], help="touch-down files to merge")
    parser.add_argument("--runs", nargs="*", type=Path, default=[],
                        help="runner JSON-lines files to summarise (no casting)")
    args = parser.parse_args(argv)
    if args.runs:
        print(runs_table(args.runs))
        return
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
