"""The single-process runner's SGIM-ACTS loop: the learner's requests answered by its experts.

Kept apart from runner.py, whose loop drives the periodic or on-request teacher, because
SGIM-ACTS's teachers only answer and the learner decides whom to ask and when. Records, one
JSON line each (the runner's ``write``), besides the evaluations:

- ``request``: the learner asks a teacher about a goal (acts_learner.Request.to_record);
- ``answer``: what the teacher showed (teaching row, action when asked for, outcome) or
  ``answered: false`` ("none there": the request still cost its price);
- ``movement``: as the runner's, plus the ``strategy`` that made it;
- ``strategy_choice``: each episode's choice once it ended (movement, strategy, teacher, mode,
  region box, goal, request, competence at its goal), the last one at the end of the run.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from .acts_episode import MAX_REQUESTS_IN_A_ROW
from .acts_learner import SgimActsLearner
from .config import LearnerConfig
from .environment import is_success
from .evaluator import Evaluator
from .experts import ARM_EXPERTS, FISHING_EXPERTS, Expert, ExpertSpec, build_experts
from .learner_registry import SGIM_ACTS as ACTS
from .learner_registry import make_learner
from .planar_arm import ARMS

EXPERTS_BY_WORLD: dict[str, tuple[ExpertSpec, ...]] = {
    "fishing": FISHING_EXPERTS, "planar-arm": ARM_EXPERTS,
    **{name: ARM_EXPERTS for name in ARMS}}
"""The teachers each world gives SGIM-ACTS (experts.py), over its teaching set."""


def experts_for(env: str, world: Any, seed: int,
                specs: Sequence[ExpertSpec] | None = None) -> dict[str, Expert]:
    """The experts of world ``env`` (EXPERTS_BY_WORLD, or ``specs``) over its teaching set."""
    if specs is None:
        if env not in EXPERTS_BY_WORLD:
            raise ValueError(f"no SGIM-ACTS teachers are specified for world {env!r} yet "
                             f"(worlds with teachers: {', '.join(EXPERTS_BY_WORLD)})")
        specs = EXPERTS_BY_WORLD[env]
    if world.teaching_actions is None:
        raise ValueError(f"world {env!r} has no teaching set to build teachers from")
    return build_experts(specs, world.teaching_actions, world.teaching_outcomes, seed,
                         world.scale.size, world.make_teacher_env, world.part_of)


def _vec(x) -> list[float] | None:
    return None if x is None else [float(v) for v in x]


def run_acts(learner: SgimActsLearner, world: Any, movements: int, eval_every: int,
             experts: Mapping[str, Expert], write: Callable[[dict[str, Any]], None],
             progress: Callable[[int], None] | None = None,
             max_requests_in_a_row: int = MAX_REQUESTS_IN_A_ROW) -> list[float]:
    """Drive ``learner`` for ``movements`` movements, answering its requests with
    ``experts``; returns the evaluation means (at 0, every ``eval_every``, at the end)."""
    missing = sorted({s.teacher for s in learner.strategies if s.social} - set(experts))
    if missing:
        raise ValueError(f"no expert answers for teacher(s) {', '.join(missing)}")
    evaluator = Evaluator(world.eval_env, world.goals, world.scale.diagonal)
    means: list[float] = []
    written = 0

    def evaluate(count: int) -> None:
        res = evaluator.evaluate(learner.inverse)
        means.append(res.mean_distance)
        write({"type": "evaluation", "movements": count, **res.to_dict()})

    def write_ended_choices() -> None:
        nonlocal written
        while written < len(learner.choices) and learner.choices[written].competence is not None:
            write(learner.choices[written].to_record())
            written += 1

    for i in range(movements):
        if eval_every > 0 and i % eval_every == 0:
            evaluate(i)
        asked = 0
        while (request := learner.request()) is not None:
            asked += 1
            if asked > max_requests_in_a_row:
                raise RuntimeError(f"sgim-acts made {max_requests_in_a_row} requests before "
                                   f"movement {i} and none gave a movement: its teachers "
                                   f"answer none there and it has no autonomous strategy")
            write(request.to_record())
            answer = experts[request.teacher].answer(request.goal, request.wants_action)
            write({"type": "answer", "request": request.index, "movement": i,
                   "teacher": request.teacher, "answered": answer is not None,
                   **({} if answer is None else answer.to_record())})
            learner.on_answer(request, answer)
            write_ended_choices()
        action, label = learner.next_action()
        result = world.env.execute(action)
        learner.observe(action, result)
        write({"type": "movement", "index": i, "label": label,
               "strategy": learner.movement_strategy, "action": _vec(action),
               "outcome": _vec(result.outcome) if is_success(result) else None,
               "status": int(result.status)})
        write_ended_choices()
        if progress is not None:
            progress(1)
    evaluate(movements)
    write_ended_choices()
    for log in learner.choices[written:]:  # the episode the budget cut short
        write(log.to_record())
    return means


def main_acts(args: argparse.Namespace, world: Any, config: LearnerConfig) -> int:
    """The runner's ``--learner sgim-acts`` (runner.main parsed ``args`` and built ``world``)."""
    from tqdm import tqdm

    strategies = (None if args.strategies is None else
                  [s.strip() for s in args.strategies.split(",") if s.strip()])
    try:
        experts = experts_for(args.env, world, args.seed)
        learner = make_learner(ACTS, world.env.action_dim, world.env.outcome_dim, args.seed,
                               config, world.scale, teachers=tuple(experts),
                               strategies=strategies)
    except ValueError as error:  # a bad --strategies, a world without teachers
        print(f"error: {error}", file=sys.stderr)
        return 2
    args.output.parent.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    with args.output.open("w") as f, tqdm(total=args.movements, disable=args.quiet,
                                           desc=ACTS, file=sys.stderr) as bar:
        def write(record: dict[str, Any]) -> None:
            f.write(json.dumps(record) + "\n")
            f.flush()

        write({"type": "header", "learner": ACTS, "env": args.env, "seed": args.seed,
               "movements": args.movements, "eval_every": args.eval_every,
               "noise": args.noise, "action_dim": world.env.action_dim,
               "outcome_dim": world.env.outcome_dim, "n_goals": len(world.goals),
               "scale": {"low": list(world.scale.low), "high": list(world.scale.high),
                         "noise": world.scale.noise},
               "experts": [{"name": e.name, "demonstrations": len(e.actions),
                            "precision": e.precision, "radius": e.radius}
                           for e in experts.values()],
               "strategies": [{"name": s.name, "cost": s.cost} for s in learner.strategies],
               "config": config.to_dict()})
        means = run_acts(learner, world, args.movements, args.eval_every, experts, write,
                         progress=bar.update)
        write({"type": "end", "final_mean_distance": means[-1], "n_memory": len(learner.memory),
               "n_requests": learner.n_requests, "n_unanswered": learner.n_unanswered,
               "cost_spent": learner.cost_spent, "n_failures": learner.n_failures,
               "elapsed_s": time.perf_counter() - start})
    if not args.quiet:
        print(f"{ACTS}: final mean distance {means[-1]:.4f}, {learner.n_requests} requests "
              f"({learner.n_unanswered} unanswered) -> {args.output}", file=sys.stderr)
    return 0
