"""How often the on-request learner's stall test holds (core/help_request.py), per seed.

Why: a learner that asks for help "when its progress stalls" is only as good as its stall test;
this runs SGIM-D with the periodic teacher, records every own goal attempt's competence, and
prints the share of sliding windows the test calls stalled (first and second half of the run)
and the median |progress| / standard error. About 0.68 is what pure noise gives.

    PYTHONPATH=sgim_nodes .venv/bin/python benchmarks/measure_help_requests.py \
        --env arm-7 --seeds 3 --movements 3000
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from sgim_nodes.core import runner
from sgim_nodes.core.help_request import DEFAULT_STALL_SE, DEFAULT_WINDOW, progress_and_error


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env", choices=runner.ENV_NAMES, default="arm-7")
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1 (default 3)")
    parser.add_argument("--movements", type=int, default=3000)
    parser.add_argument("--period", type=int, default=150, help="the teacher's P")
    parser.add_argument("--window", type=int, default=DEFAULT_WINDOW)
    parser.add_argument("--stall-se", type=float, default=DEFAULT_STALL_SE)
    args = parser.parse_args(argv)
    if args.seeds < 1 or args.movements < 1 or args.window < 4 or args.window % 2:
        parser.error("--seeds and --movements must be >= 1, --window even and >= 4")
    for seed in range(args.seeds):
        world = runner.build_world(args.env, seed)
        learner = runner.make_learner("sgim-d", world.env.action_dim, world.env.outcome_dim,
                                      seed, None, world.scale)
        competences: list[float] = []
        learner.attempt_listeners.append(
            lambda _goal, c, into=competences: into.append(c))
        runner.run(learner, world, args.movements, 0, seed, lambda _r: None,
                   teacher_period=args.period)
        c = np.asarray(competences)
        w = args.window
        ratios = []
        for end in range(w, len(c) + 1):
            gap, se = progress_and_error(c[end - w:end])
            ratios.append(gap / se if se > 0 else (0.0 if gap == 0 else np.inf))
        stalled = np.asarray(ratios) <= args.stall_se
        half = len(stalled) // 2
        print(f"{args.env} seed {seed}: {len(c)} goal attempts, stalled in "
              f"{stalled.mean():.2f} of {len(stalled)} windows (first half "
              f"{stalled[:half].mean():.2f}, second {stalled[half:].mean():.2f}); "
              f"median |progress| / SE {np.median(ratios):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
