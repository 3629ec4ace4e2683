"""How noisy is the benchmark's "ours against the nearest neighbour on the same memory" line?

bench_learners.py compares, on each final memory, the learner's inverse model with the plain
nearest neighbour, with 2 noisy casts per goal on the fishing world; in a few runs ours came out
worse. Here one learner's memory is compared ``--repeats`` times, each time in a fresh
evaluation world with its own seed (both models in worlds of the same seed, as the benchmark
does), to see how often the 2-cast verdict flips and how large the gap is against its own
spread. The actions of both models are computed once: only the casts' noise differs between
repeats. A third model, ours without its local-linear step (the candidate it ranks best,
that pair's own action), tells the ranking's share of the gap from the step's, a fourth,
ours without the gates on thin fits (``local_min_casts`` and ``local_rank_min_casts`` 0),
the gates' share,
a fifth, ours without the held-out check of its step (``local_step_check: none``), and a
sixth, ours with its step bounded by twice the fit's spread (``local_step_support: 2``).
``--goals validation`` (fishing) compares them on other points of the benchmark's grid cells
(its tool's ``validation_goals``, seed 7), so that a choice made here is not made on the
benchmark's own goals.
``--learn-set NAME=VALUE`` changes the learning run's LearnerConfig (e.g. local_min_casts=0 to
learn the memory the way the learner did before the gate).

Run: PYTHONPATH=sgim_nodes:sim_bridge .venv/bin/python benchmarks/measure_same_memory.py \\
         --learner saggriac --seed 0 --movements 2000 --repeats 10 [--learn-set NAME=VALUE]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(REPO / "sgim_nodes"), str(REPO / "sim_bridge")]

from sgim_nodes.core.config import LearnerConfig  # noqa: E402
from sgim_nodes.core.evaluator import EVALUATION_SEED_OFFSET, Evaluator  # noqa: E402
from sgim_nodes.core.inverse_model import InverseModel  # noqa: E402
from sgim_nodes.core.learners import inverse_model_for, make_learner  # noqa: E402
from sgim_nodes.core.runner import build_world, run  # noqa: E402

sys.path.insert(0, str(REPO / "benchmarks"))
from bench_learners import goals_for, parse_set  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--world", default="fishing")
    p.add_argument("--learner", default="saggriac")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--movements", type=int, default=2000)
    p.add_argument("--repeats", type=int, default=10)
    p.add_argument("--casts", type=int, default=2, help="casts per goal and repeat (bench: 2)")
    p.add_argument("--goals", choices=("benchmark", "validation"), default="benchmark",
                   help="fishing: the benchmark goals, or other points of their cells (seed 7)")
    p.add_argument("--learn-set", action="append", default=[], metavar="NAME=VALUE",
                   help="a LearnerConfig value for the learning run (repeatable)")
    a = p.parse_args()
    if a.goals == "validation" and a.world != "fishing":
        raise SystemExit("--goals validation: the fishing world only (the arms: bench_inverse)")
    start = time.perf_counter()
    world = build_world(a.world, a.seed)
    learner = make_learner(a.learner, world.env.action_dim, world.env.outcome_dim, a.seed,
                           LearnerConfig(**parse_set(a.learn_set)), world.scale)
    run(learner, world, a.movements, 0, a.seed, lambda record: None)
    ours = inverse_model_for(learner.memory, LearnerConfig(), world.scale)  # the default model
    # ours without its local-linear step: the candidate it ranks best, that pair's own action
    unmoved = InverseModel(learner.memory, "local-linear", ours.l_max, ours.k_max, ours.alpha,
                           ours.local_radius, ours.local_neighbours, 1e-12, ours.min_casts,
                           ours.noise_rms, ours.rank_min_casts, ours.step_support)
    ungated = InverseModel(learner.memory, "local-linear", ours.l_max, ours.k_max, ours.alpha,
                           ours.local_radius, ours.local_neighbours, ours.local_step, 0.0,
                           ours.noise_rms, 0.0, ours.step_support)
    unchecked = inverse_model_for(learner.memory, LearnerConfig(local_step_check="none"),
                                  world.scale)
    supported = inverse_model_for(learner.memory, LearnerConfig(local_step_support=2.0),
                                  world.scale)
    models = {"ours": ours, "nearest": InverseModel(learner.memory, "nearest"),
              "ours-no-step": unmoved, "ours-no-gate": ungated, "ours-unchecked": unchecked,
              "ours-support-2": supported}
    goals = world.goals if a.goals == "benchmark" else goals_for(a.world, "validation")[1]
    actions = {label: {tuple(g): np.asarray(m(g), float) for g in goals}
               for label, m in models.items()}
    same = np.mean([np.array_equal(actions["ours"][k], actions["nearest"][k])
                    for k in actions["ours"]])
    print(f"{a.world} {a.learner} seed {a.seed}, memory of {len(learner.memory)} pairs after "
          f"{a.movements} movements; ours and nearest give the same action for "
          f"{same:.2f} of the {len(goals)} {a.goals} goals")
    rows = []
    for r in range(a.repeats):
        out = {}
        for label in models:
            fresh = build_world(a.world, 10_000 + EVALUATION_SEED_OFFSET + r)
            ev = Evaluator(fresh.eval_env, goals, world.scale.diagonal)
            out[label] = float(np.mean([ev.evaluate(lambda g, lab=label: actions[lab][tuple(g)])
                                        .mean_distance for _ in range(a.casts)]))
            if hasattr(fresh.env, "close"):
                fresh.env.close()
                fresh.eval_env.close()
        rows.append(out)
        print(f"  repeat {r}: " + ", ".join(f"{k} {v:.4f}" for k, v in out.items()))
        sys.stdout.flush()
    print(f"over {a.repeats} repeats of {a.casts} casts per goal "
          f"({time.perf_counter() - start:.0f} s):")
    near = np.array([o["nearest"] for o in rows])
    for label in models:
        v = np.array([o[label] for o in rows])
        d = v - near
        sd = d.std(ddof=1) if len(d) > 1 else 0.0
        print(f"  {label:15s} {v.mean():.4f}; minus nearest {d.mean():+.4f} (sd {sd:.4f} per "
              f"repeat), no worse in {int(np.sum(d <= 0))}/{a.repeats} repeats")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
