"""SGIM-D on your own world, without ROS: a toy 2-joint arm, a teacher and an evaluation.

The learner only needs an object with ``action_dim``, ``outcome_dim`` and
``execute(action) -> result`` (``sgim_nodes.core.environment.Environment``): put your robot
or simulator behind those three names and the code below runs unchanged.

    pip install ./sgim_nodes                  # numpy and scipy; no ROS needed
    python examples/own_environment.py        # a few seconds; --help for the options

It prints the benchmark's mean error (the distance from each goal to where the hand lands
when the learner aims at it) as the learner practises, and the number of demonstrations.
"""

from __future__ import annotations

import argparse

import numpy as np

from sgim_nodes.core.environment import MovementResult
from sgim_nodes.core.learner_registry import SGIM_D, make_learner
from sgim_nodes.core.runner import World, run
from sgim_nodes.core.scale import WorldScale, gaussian_noise_2d
from sgim_nodes.core.social_config import SocialConfig

NOISE = 0.01  # standard deviation of the hand's landing point, per axis


class TwoJointArm:
    """Your world. Actions are in [-1, 1]^action_dim; the outcome is where the hand lands."""

    action_dim, outcome_dim = 2, 2

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def execute(self, action: np.ndarray) -> MovementResult:
        shoulder, elbow = np.clip(action, -1.0, 1.0) * (np.pi, 0.75 * np.pi)
        hand = 0.5 * np.array([np.cos(shoulder) + np.cos(shoulder + elbow),
                               np.sin(shoulder) + np.sin(shoulder + elbow)])
        return MovementResult(hand + self.rng.normal(0.0, NOISE, 2))  # status OK by default


def learn(movements: int, seed: int) -> tuple[list[tuple[int, float]], int]:
    """SGIM-D on the arm: returns (movements, mean error) per evaluation, and the number of
    demonstrations the teacher gave."""
    # The outcome box the learner explores, and the world's noise (the precision worth asking).
    scale = WorldScale.box(low=(-1, -1), high=(1, 1), noise=gaussian_noise_2d(NOISE))
    # The teacher's demonstrations: actions shown to the robot and where they landed.
    shown = np.random.default_rng(1000 + seed).uniform(-1.0, 1.0, (30, 2))
    landed = np.array([TwoJointArm(seed=2000 + seed).execute(a).outcome for a in shown])
    # The benchmark: goals on a grid over the reachable ring, never used for learning.
    grid = np.stack(np.meshgrid(*[np.linspace(-0.9, 0.9, 10)] * 2), -1).reshape(-1, 2)
    goals = grid[(np.hypot(*grid.T) > 0.3) & (np.hypot(*grid.T) < 0.95)]
    world = World(env=TwoJointArm(seed), eval_env=TwoJointArm(seed + 1), goals=goals,
                  teaching_actions=shown, teaching_outcomes=landed, scale=scale,
                  make_teacher_env=lambda: TwoJointArm(seed + 2))  # the teacher checks here
    learner = make_learner(SGIM_D, TwoJointArm.action_dim, TwoJointArm.outcome_dim,
                           seed, scale=scale)
    records: list[dict] = []  # every movement, demonstration and evaluation, as plain dicts
    run(learner, world, movements, eval_every=250, seed=seed, write=records.append,
        social=SocialConfig())  # the paper's teacher: a demonstration every 150 movements
    curve = [(r["movements"], r["mean_distance"]) for r in records if r["type"] == "evaluation"]
    return curve, sum(r["type"] == "demonstration" for r in records)


def main() -> None:
    parser = argparse.ArgumentParser(description="SGIM-D on a toy 2-joint arm, without ROS.")
    parser.add_argument("--movements", type=int, default=1500,
                        help="movements the learner makes (default: %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    args = parser.parse_args()
    if args.movements < 1:
        parser.error("--movements must be >= 1")
    curve, demonstrations = learn(args.movements, args.seed)
    for count, error in curve:
        print(f"after {count:5d} movements: mean error {error:.4f}")
    print(f"first error {curve[0][1]:.4f}, final error {curve[-1][1]:.4f}, "
          f"{demonstrations} demonstrations")


if __name__ == "__main__":
    main()
