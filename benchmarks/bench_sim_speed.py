"""Casts per second of the fishing world, in-process on one core, with an optional profile.

Why: four learners x ten seeds x 5000 movements must run on a laptop; the target is >= 50 casts/s.

    .venv/bin/python benchmarks/bench_sim_speed.py --casts 500 [--profile]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

from sim_bridge.fishing_world import FishingWorld


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--casts", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--profile", action="store_true", help="print the top cProfile entries")
    args = parser.parse_args(argv)
    world = FishingWorld(seed=args.seed)
    acts = np.random.default_rng(args.seed).uniform(-1, 1, (args.casts, world.action_dim))
    world.execute(acts[0])  # warm-up
    prof = cProfile.Profile() if args.profile else None
    t0 = time.perf_counter()
    if prof:
        prof.enable()
    for a in acts:
        world.execute(a)
    if prof:
        prof.disable()
    el = time.perf_counter() - t0
    print(f"{args.casts / el:.1f} casts/s, {1000 * el / args.casts:.2f} ms per cast"
          f"{' (under the profiler)' if prof else ''}")
    if prof:
        pstats.Stats(prof).sort_stats("tottime").print_stats(8)


if __name__ == "__main__":
    main()
