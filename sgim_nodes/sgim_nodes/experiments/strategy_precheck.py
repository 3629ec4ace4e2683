"""Pre-check of SGIM-ACTS's strategy value, before any learning run: on goals of an expert's
own part of the lake, does the value rank that expert above the rough teacher, who knows the
whole lake but shows imprecise casts? Once with the gain (LearnerConfig.strategy_value
``gain``), once with eq. 2's interest (the lineage's).

Per seed: an SGIM-ACTS learner warms up on the fishing world with movements of its own (its
own choice of goals, every episode autonomous, no teacher); then, for each expert with a part
(experts.FISHING_EXPERTS), goals are drawn uniformly inside that part from the seed's own
stream, and every strategy, forced rather than chosen, attempts them in order, each strategy
from a copy of the same warmed learner, world and experts, so that the strategies differ only
by how they learn. Each strategy's competences go into a StrategyRegions history over the part,
whose gain and interest are the core's.

The benchmark goals are never used: the world's are dropped as soon as it is built, and
nothing is evaluated.

    python -m sgim_nodes.experiments.strategy_precheck --seeds 10-19
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sgim_nodes.core.acts_learner import SgimActsLearner
from sgim_nodes.core.acts_runner import experts_for
from sgim_nodes.core.config import LearnerConfig
from sgim_nodes.core.experts import FISHING_EXPERTS, Expert, ExpertSpec
from sgim_nodes.core.learner_registry import SGIM_ACTS, make_learner
from sgim_nodes.core.random_streams import member_rng
from sgim_nodes.core.region_tree import RegionTree
from sgim_nodes.core.runner import build_world
from sgim_nodes.core.strategies import AUTONOMOUS, EMULATION, MIMICRY
from sgim_nodes.core.strategy_choice import PairChoice
from sgim_nodes.core.strategy_regions import StrategyRegions

ENV = "fishing"
ROUGH = "rough"
FORCED_MODE = 0
"""The mode a forced episode logs: none of the three chose it."""
MAX_DRAWS = 1_000_000
"""Uniform draws allowed per goal inside a part before giving up (a part too small to hit)."""


@dataclass(frozen=True)
class PartResult:
    """One seed's histories over one expert's part: each strategy's gain and interest."""

    seed: int
    expert: str
    parts: tuple[str, ...]
    goals: int
    gain: dict[str, float]
    interest: dict[str, float]
    episodes: dict[str, int]  # competences in each strategy's history

    def above_rough(self, kind: str, value: str) -> bool:
        """Whether ``value`` ranks ``kind`` of the part's own expert strictly above rough's."""
        values = self.gain if value == "gain" else self.interest
        return values[f"{kind}:{self.expert}"] > values[f"{kind}:{ROUGH}"]


def parse_seeds(text: str) -> list[int]:
    """``10-19`` (both ends included), ``3,5,7`` or a mix of them."""
    seeds: list[int] = []
    for item in text.split(","):
        first, dash, last = item.strip().partition("-")
        try:
            low, high = int(first), int(last if dash else first)
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad seeds {text!r}: write e.g. 10-19 or "
                                             "3,5,7") from None
        if low > high:
            raise argparse.ArgumentTypeError(f"bad seed range {item!r}: {low} > {high}")
        seeds += range(low, high + 1)
    return seeds


def part_goals(world: Any, parts: Sequence[str], count: int,
               rng: np.random.Generator) -> np.ndarray:
    """``count`` goals uniform over the outcome box, kept only inside the named ``parts``."""
    low, high = world.scale.low_array, world.scale.high_array
    goals = []
    for _ in range(MAX_DRAWS):
        if len(goals) == count:
            return np.array(goals).reshape(count, len(low))
        goal = rng.uniform(low, high)
        if world.part_of(goal) in parts:
            goals.append(goal)
    raise RuntimeError(f"{MAX_DRAWS} draws gave fewer than {count} goals in {parts}")


def move(learner: SgimActsLearner, env: Any) -> None:
    action, _ = learner.next_action()
    learner.observe(action, env.execute(action))


def warm_up(learner: SgimActsLearner, env: Any, movements: int) -> None:
    """``movements`` of the learner's own: its chooser's goals, every episode autonomous;
    the last episode runs to its end, so that the trials begin episodes of their own."""
    autonomous = next(s for s in learner.strategies if s.kind == AUTONOMOUS)
    while learner.n_movements < movements or not (learner.episode is None
                                                  or learner.episode.done):
        if learner.episode is None or learner.episode.done:
            choice = learner.chooser.sample(learner.choice_rng)
            learner.begin(dataclasses.replace(choice, strategy=autonomous))
        move(learner, env)


def forced_episode(learner: SgimActsLearner, env: Any, experts: dict[str, Expert],
                   strategy: str, goal: np.ndarray) -> float:
    """One episode of ``strategy`` at ``goal``, its teacher answering; its competence."""
    chosen = next(s for s in learner.strategies if s.name == strategy)
    leaf = learner.regions.tree.leaf_for(goal)
    index = len(learner.choices)
    request = learner.begin(PairChoice(chosen, goal, FORCED_MODE,
                                       learner.regions.leaves.index(leaf), leaf))
    if request is not None:
        learner.on_answer(request, experts[request.teacher].answer(request.goal,
                                                                   request.wants_action))
    while not learner.episode.done:
        move(learner, env)
    return learner.choices[index].competence


def check_seed(seed: int, warmup: int, n_goals: int,
               config: LearnerConfig) -> list[PartResult]:
    world = build_world(ENV, seed)
    world = dataclasses.replace(world, goals=np.empty((0, world.scale.dim)))  # never seen
    experts = experts_for(ENV, world, seed)
    learner = make_learner(SGIM_ACTS, world.env.action_dim, world.env.outcome_dim, seed,
                           config, world.scale, teachers=tuple(experts))
    warm_up(learner, world.env, warmup)
    rng = member_rng(seed, "goals", "strategy-precheck")
    results = []
    for spec in parted_experts():
        goals = part_goals(world, spec.named_parts, n_goals, rng)
        names = [s.name for s in learner.strategies]
        tree = RegionTree(world.scale.low_array, world.scale.high_array,
                          len(names) * n_goals + config.zeta, config.zeta)
        histories = StrategyRegions(tree, names)  # one leaf: the part's goals, never split
        for name in names:  # each from the same warmed state
            trial, env, answers = copy.deepcopy((learner, world.env, experts))
            for goal in goals:
                histories.add(name, goal, forced_episode(trial, env, answers, name, goal))
        leaf = histories.leaves[0]
        results.append(PartResult(seed, spec.name, spec.named_parts, n_goals,
                                  {n: histories.gain(n, leaf) for n in names},
                                  {n: histories.interest(n, leaf) for n in names},
                                  {n: len(histories.history(n, leaf)) for n in names}))
    return results


def parted_experts() -> tuple[ExpertSpec, ...]:
    """The fishing experts who know a part of the lake (not rough, who knows it all)."""
    return tuple(spec for spec in FISHING_EXPERTS if spec.named_parts)


def ranking(values: dict[str, float]) -> str:
    ordered = sorted(values.items(), key=lambda item: (-item[1], item[0]))
    return " > ".join(f"{name} {value:.4f}" for name, value in ordered)


def report(result: PartResult) -> str:
    lines = [f"seed {result.seed}, part of {result.expert} ({'+'.join(result.parts)}), "
             f"{result.goals} goals",
             f"  gain:  {ranking(result.gain)}",
             f"  eq. 2: {ranking(result.interest)}"]
    for kind in (MIMICRY, EMULATION):
        lines.append(f"  {kind}: {result.expert} above {ROUGH}? gain "
                     f"{'yes' if result.above_rough(kind, 'gain') else 'no'}, eq. 2 "
                     f"{'yes' if result.above_rough(kind, 'interest') else 'no'}")
    return "\n".join(lines)


def summary(results: Sequence[PartResult]) -> list[str]:
    n = len(results)
    lines = []
    for kind in (MIMICRY, EMULATION):
        gain = sum(r.above_rough(kind, "gain") for r in results)
        eq2 = sum(r.above_rough(kind, "interest") for r in results)
        lines.append(f"{kind}: own expert above {ROUGH} in {gain} of {n} comparisons with "
                     f"the gain value, {eq2} of {n} with eq. 2")
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m sgim_nodes.experiments.strategy_precheck",
        description="Does the gain value, or eq. 2's interest, rank a part's own expert "
                    "above the rough teacher on goals of that part? (fishing world; no "
                    "benchmark goal is used)")
    p.add_argument("--seeds", type=parse_seeds, default=parse_seeds("10-19"),
                   help="seeds, e.g. 10-19 or 3,5,7 (default: 10-19)")
    p.add_argument("--warmup", type=int, default=200,
                   help="autonomous movements before the trials (default: 200)")
    p.add_argument("--goals", type=int, default=16,
                   help="goals drawn in each expert's part (default: 16)")
    args = p.parse_args(argv)
    if args.warmup < 0 or args.goals < 2:
        p.error("--warmup must be >= 0 and --goals >= 2 (eq. 2 needs two halves)")
    results = []
    for seed in args.seeds:
        for result in check_seed(seed, args.warmup, args.goals, LearnerConfig()):
            print(report(result), flush=True)
            results.append(result)
    for line in summary(results):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
