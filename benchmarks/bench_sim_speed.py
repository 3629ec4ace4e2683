"""Casts per second of the fishing world, in-process on one core, with an optional profile.

Why: the study (five learners x ten seeds x 5000 movements) must run in minutes on 2 cores; the
target is >= 150 casts/s (issue 11). Wall-clock casts/s is the figure; the CPU time of this
process is printed beside it because, on a machine shared with other jobs, the wall clock also
counts the time this process waited for a core (compare the two to see how loaded the machine
was). ``--repeat N`` runs the same casts N times and prints each and the best.
``--accuracy N`` also casts N random actions without noise in this world and in one whose
constraint solver has converged (MLCP with 300 Gauss-Seidel sweeps), and prints how far the
touch-downs differ. ``--solver gauss-seidel`` measures the world's previous solver (50 sweeps)
beside its own, Dantzig's pivoting (``shipped`` or ``dantzig``).
``--shared-world N`` times a bare ``stepSimulation`` of 1, 2, 4, ... N copies of the rod in
ONE world, per step and per rod: could independent casts (the evaluation's goals) be batched?

    PYTHONPATH=sim_bridge .venv/bin/python benchmarks/bench_sim_speed.py --casts 500 [--profile]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np
import pybullet as pb

from sim_bridge.fishing_world import SOLVER_ITERATIONS, FishingWorld, _quiet_c_stdout

SOLVERS = ("shipped", "dantzig", "gauss-seidel")
"""``--solver``: the world as built (Dantzig's pivoting since issue 32), or either solver by name
(``set_solver``)."""


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--casts", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=1, help="timed rounds (best is printed)")
    parser.add_argument("--profile", action="store_true", help="print the top cProfile entries")
    parser.add_argument("--accuracy", type=int, default=0,
                        help="casts compared with a converged solver (0: skip)")
    parser.add_argument("--solver", choices=SOLVERS, default="shipped",
                        help="constraint solver: the world's own (Dantzig's pivoting), "
                        "'dantzig' (the same, named), or 'gauss-seidel' (the previous one: "
                        "MLCP with 50 projected Gauss-Seidel sweeps; README_world.md, Speed)")
    parser.add_argument("--shared-world", type=int, default=0, metavar="N",
                        help="only time bare steps of 1, 2, 4, ... N rods in one world")
    args = parser.parse_args(argv)
    if args.casts < 1 or args.repeat < 1 or args.shared_world < 0:
        parser.error("--casts and --repeat must be >= 1, --shared-world >= 0")
    if args.shared_world:
        for line in shared_world_steps(args.shared_world):
            print(line, flush=True)
        return
    world = FishingWorld(seed=args.seed)
    if args.solver != "shipped":
        set_solver(world, args.solver)
    acts = np.random.default_rng(args.seed).uniform(-1, 1, (args.casts, world.action_dim))
    world.execute(acts[0])  # warm-up
    prof = cProfile.Profile() if args.profile else None
    best = (0.0, 0.0)
    for _ in range(args.repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        if prof:
            prof.enable()
        for a in acts:
            world.execute(a)
        if prof:
            prof.disable()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        best = max(best, (args.casts / wall, args.casts / cpu))
        print(f"{args.casts / wall:.1f} casts/s, {1000 * wall / args.casts:.2f} ms per cast "
              f"(CPU time of this process: {args.casts / cpu:.1f} casts/s)"
              f"{' (under the profiler)' if prof else ''}", flush=True)
    if args.repeat > 1:
        print(f"best of {args.repeat}: {best[0]:.1f} casts/s (CPU: {best[1]:.1f} casts/s)")
    if prof:
        pstats.Stats(prof).sort_stats("tottime").print_stats(10)
    if args.accuracy > 0:
        print(solver_accuracy(args.accuracy, args.seed, args.solver))


def shared_world_steps(most: int, steps: int = 2000) -> list[str]:
    """Bare stepSimulation time with 1, 2, 4, ... ``most`` rods in one world, at rest. Each
    rod is built by FishingWorld's own construction (its solver, gravity, freed passive
    joints) in the same physics client; the model has no collision shapes, so the rods do
    not touch."""
    from sim_bridge.rod_urdf import RodSpec

    lines, n = [], 1
    while n <= most:
        with FishingWorld(seed=0) as world:
            for _ in range(n - 1):
                world._build(RodSpec())
            c = world._client
            for _ in range(50):
                pb.stepSimulation(c)
            t0 = time.process_time()
            for _ in range(steps):
                pb.stepSimulation(c)
            per_step = (time.process_time() - t0) / steps
        lines.append(f"{n:3d} rods in one world: {1e6 * per_step:7.1f} us per step, "
                     f"{1e6 * per_step / n:5.1f} us per rod and step (CPU time)")
        n *= 2
    return lines


def set_solver(world: FishingWorld, solver: str, sweeps: int = SOLVER_ITERATIONS) -> None:
    """Switch a built world's constraint solver: ``dantzig`` (MLCP solved by Dantzig's
    pivoting, the world's own) or ``gauss-seidel`` (MLCP with ``sweeps`` projected Gauss-Seidel
    sweeps: with the default 50, the world's solver before issue 32), so that the two can still
    be compared; the rest state is saved again, as each cast restores it."""
    kind = {"dantzig": pb.CONSTRAINT_SOLVER_LCP_DANTZIG,
            "gauss-seidel": pb.CONSTRAINT_SOLVER_LCP_PGS}
    with _quiet_c_stdout():  # pybullet prints "switched solver" from C
        pb.setPhysicsEngineParameter(constraintSolverType=kind[solver],
                                     numSolverIterations=sweeps, physicsClientId=world._client)
    world._state = pb.saveState(physicsClientId=world._client)


def solver_accuracy(n: int, seed: int, solver: str = "shipped") -> str:
    """Touch-down distance (normalised units) between the world with `solver` and one whose
    solver has converged (MLCP with 300 Gauss-Seidel sweeps)."""
    from sim_bridge.scaling import world_to_outcome

    acts = np.random.default_rng(seed + 1).uniform(-1, 1, (n, 24))
    pts = []
    for reference in (False, True):
        with FishingWorld(seed=seed, noise=0.0) as w:
            if reference:
                set_solver(w, "gauss-seidel", sweeps=300)
            elif solver != "shipped":
                set_solver(w, solver)
            pts.append(np.array([world_to_outcome(r.world_point) if r.world_point is not None
                                 else (np.nan, np.nan) for r in map(w.execute, acts)]))
    d = np.linalg.norm(pts[0] - pts[1], axis=1)
    d = d[np.isfinite(d)]
    return (f"{solver} solver vs 300 sweeps ({len(d)} noise-free touch-downs): median "
            f"{np.median(d):.5f}, p90 {np.percentile(d, 90):.5f}, p99 "
            f"{np.percentile(d, 99):.4f}, max {d.max():.4f}")


if __name__ == "__main__":
    main()
