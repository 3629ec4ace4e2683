"""Single-process runner: one learner, one world, no ROS.

Used by tests, benchmarks and to compare with the ROS graph.  Every movement, demonstration,
teacher's check ("teacher_check": one per teaching goal at each turn, as the graph's
teacher_checks) and evaluation is written as one JSON line and flushed at once, so a killed
run keeps all it did.  The loop itself (``run``) writes through a callback so tests can keep
records in memory.

Example:
    python -m sgim_nodes.core.runner --learner sgim-d --movements 5000 --seed 3 \
        --env planar-arm --eval-every 250 --output runs/sgimd_3.jsonl
    (``--learner sgim-acts`` asks its own teachers: core/acts_runner.py)
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from .config import LearnerConfig
from .environment import is_success
from .evaluator import Evaluator
from .help_request import ON_REQUEST, budget_for
from .learner_base import Learner
from .learner_registry import SGIM_D, learner_kind, learner_names, make_learner
from .random_streams import SEED_MAX, component_rng
from .repeatable_casts import RepeatableCasts
from .schedule import Schedule
from .social_config import SOCIAL_DEFAULTS, SocialConfig, declared, turn_names
from .teaching import (
    ABILITY,
    Teacher,
    Turn,
    learner_progress,
)
from .worlds import World, WorldMissing, build_world, world_names

EVALUATION = "evaluation"
SOCIAL_OPTIONS = ("demonstration_period", "reached_rule", "teacher_choice",
                  "demonstration_content", "timing", "tolerance_noise")
"""The SocialConfig settings the command line takes, each as --NAME (underscores as dashes)."""


def _vec(x: np.ndarray | None) -> list[float] | None:
    return None if x is None else [float(v) for v in np.asarray(x).ravel()]


def check_records(turn: Turn, movement: int, ask: int, rule: str, choice: str
                  ) -> list[dict[str, Any]]:
    """A teacher's turn as "teacher_check" records, one per teaching goal, written before its
    demonstration: what TeacherCheck messages carry in the graph's bag (teacher_checks), so an
    auditor redoes the turn from them alone (teaching.eligible) and compares both."""
    common = {"type": "teacher_check", "movement": movement, "help_request": ask,
              "asked_goal": _vec(turn.asked), "rule": rule, "choice": choice,
              "entries": len(turn.checks)}
    return [{**common, **check.to_dict(), "chosen": check.index == turn.chosen}
            for check in turn.checks]


def run(learner: Learner, world: World, movements: int, eval_every: int,
        seed: int, write: Callable[[dict[str, Any]], None],
        social: SocialConfig = SOCIAL_DEFAULTS,
        progress: Callable[[int], None] | None = None) -> list[float]:
    """Drive ``learner`` for ``movements`` movements; returns the evaluation means.

    Evaluations happen at 0, every ``eval_every`` movements and at the end. A social learner
    hears the teacher as ``social`` says (core/social_config.py): at every turn of its period
    (movements 0, P, 2P, ...) the teacher shows, if some teaching goal is unreached under its
    reached rule, the one its choice picks, with what the demonstration content says
    (core/teaching.py); on request, only when the learner asks (core/help_request.py), at most
    as many times as the periodic teacher's turns; several teachers may take the turns
    (core/teacher_turns.py, ExpertSpec values).
    """
    c = social
    refusal = learner_kind(learner.name).refusal(c.timing, c.demonstration_content)
    if refusal:
        raise ValueError(refusal)
    teacher, teacher_env = None, None
    if learner.social and world.teaching_actions is not None:
        tolerance = c.tolerance_noise * world.scale.noise
        if c.teacher_turns:
            from .teacher_turns import TeacherTurns

            teacher = TeacherTurns(c.teacher_turns, world.teaching_actions,
                                   world.teaching_outcomes, seed, c.demonstration_period,
                                   tolerance, c.teacher_choice, world.make_teacher_env,
                                   world.part_of)
        else:
            teacher = Teacher(world.teaching_actions, world.teaching_outcomes,
                              component_rng(seed, "teacher"), c.demonstration_period,
                              tolerance, c.teacher_choice)
        if c.reached_rule == ABILITY:
            if world.make_teacher_env is None:
                raise ValueError("the teacher's 'ability' rule needs world.make_teacher_env")
            # One for the whole run: an answer unchanged since the last turn is not cast again.
            teacher_env = RepeatableCasts(world.make_teacher_env())
    try:
        schedule = Schedule(movements, c.demonstration_period, c.timing, teacher is not None)
        if schedule.help is not None:
            learner.attempt_listeners.append(schedule.attempt_ended)
        return _run(learner, world, movements, eval_every, write, teacher, c.reached_rule,
                    teacher_env, progress, c.demonstration_content, schedule)
    finally:
        if teacher_env is not None and hasattr(teacher_env, "close"):
            teacher_env.close()


def _run(learner: Learner, world: World, movements: int, eval_every: int,
         write: Callable[[dict[str, Any]], None], teacher: Teacher | None, teacher_rule: str,
         teacher_env: RepeatableCasts | None, progress: Callable[[int], None] | None,
         content: str, schedule: Schedule) -> list[float]:
    evaluator = Evaluator(world.eval_env, world.goals, world.scale.diagonal)
    means: list[float] = []

    def evaluate(count: int) -> None:
        res = evaluator.evaluate(learner.inverse)
        means.append(res.mean_distance)
        write({"type": EVALUATION, "movements": count, **res.to_dict()})

    for i in range(movements):
        if eval_every > 0 and i % eval_every == 0:
            evaluate(i)
        turn, asked, ask = None, None, 0
        if schedule.turn_due(i):
            schedule.take_turn(i)
            learner.on_teacher_turn()
            turn = teacher.decide(learner_progress(teacher_rule, learner.inverse,
                                                   learner.own_outcomes, teacher_env))
        elif schedule.ask_due(i):
            question = schedule.ask(i)
            asked, ask = question.goal, question.index
            # The ask ends the goal attempt under way, answered or not, as a teacher's turn
            # does (core/schedule.py).
            learner.on_teacher_turn()
            write({"type": "help_request", "movement": i, "ask": ask, "goal": _vec(asked)})
            turn = teacher.decide(learner_progress(teacher_rule, learner.inverse,
                                                   learner.own_outcomes, teacher_env), asked)
        demo = None if turn is None else turn.demonstration
        if turn is not None:
            for record in check_records(turn, i, ask, teacher_rule, teacher.choice):
                write(record)
        if demo is not None:
            action, outcome = demo.shown(content)
            learner.on_demonstration(action, outcome)
            write({"type": "demonstration", "movement": i, "teaching_index": demo.index,
                   "content": content, "action": _vec(action), "outcome": _vec(outcome),
                   **({"teacher": demo.teacher} if getattr(demo, "teacher", "") else {}),
                   **({} if asked is None else {"asked_goal": _vec(asked)})})
        action, label = learner.next_action()
        result = world.env.execute(action)
        learner.observe(action, result)
        write({"type": "movement", "index": i, "label": label, "action": _vec(action),
               "outcome": _vec(result.outcome) if is_success(result) else None,
               "status": int(result.status)})
        if progress is not None:
            progress(1)
    evaluate(movements)
    return means


class BriefParser(argparse.ArgumentParser):
    """argparse whose refusal is one line, `PROG: error: MESSAGE (see PROG --help)`, exit code
    2, not the whole usage before it (as sgim_ros's parser of the ROS commands: the core
    imports no ROS package)."""

    def error(self, message: str) -> NoReturn:
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in message)
        self.exit(2, f"{self.prog}: error: {text} (see {self.prog} --help)\n")


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    p = BriefParser(
        prog="sgim-learn",
        description="Run one learner on one world without ROS and log every movement and "
                    "evaluation as JSON lines (flushed as it goes).")
    p.add_argument("--learner", choices=learner_names(), default=SGIM_D,
                   help="which learner to run (default: %(default)s)")
    p.add_argument("--strategies", default=None,
                   help="sgim-acts: comma-separated strategies, e.g. autonomous,mimicry:west "
                        "(default: autonomous and both social ones of every teacher)")
    p.add_argument("--movements", type=int, default=5000,
                   help="number of movements, the paper's budget is 5000 (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of every random draw of the run (default: %(default)s)")
    p.add_argument("--env", choices=world_names(), default="planar-arm",
                   help="world: 'fishing' needs sim_bridge; 'planar-arm' (the small test "
                        "arm), 'arm-7' and 'arm-20' (the benchmark arms) are analytic "
                        "(default: %(default)s)")
    p.add_argument("--eval-every", type=int, default=250,
                   help="evaluate every N movements, 0 = only at start and end; the paper "
                        "uses 250 (default: %(default)s)")
    p.add_argument("--output", type=Path, required=True, help="JSON-lines file to write")
    p.add_argument("--noise", type=float, default=None,
                   help="outcome noise of the world (default: the world's own default)")
    p.add_argument("--pond-radius", type=float, default=None,
                   help="fishing: radius in metres of the isolated pond (default: the world's "
                        "own, 0.95); benchmark and teaching sets come from SIM_BRIDGE_DATA_DIR")
    p.add_argument("--arm-joints", type=int, default=12,
                   help="planar-arm: number of joints (default: %(default)s)")
    for name in SOCIAL_OPTIONS:  # the teacher's settings, as core/social_config.py declares
        d = declared(name)
        choices = d["range"].choices or None
        p.add_argument("--" + name.replace("_", "-"), default=d["default"], choices=choices,
                       type=None if choices else type(d["default"]),
                       help=f"{d['help']} (SocialConfig.{name}; default: %(default)s)")
    p.add_argument("--teacher-turns", default="",
                   help="several teachers take the teacher's turns, in this order: "
                        "comma-separated names of the world's SGIM-ACTS experts, e.g. "
                        "centre,west,rough on fishing (core/teacher_turns.py; default: one "
                        "teacher who knows the whole teaching set)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    args = p.parse_args(argv)
    if args.movements < 0:
        p.error("--movements must be >= 0")
    if not 0 <= args.seed <= SEED_MAX:
        p.error(f"--seed must be in 0..{SEED_MAX} (2**32 - 1): the graph's range, so that "
                "a seed of `learn` is one a graph run takes too")
    if args.eval_every < 0:
        p.error("--eval-every must be >= 0")
    try:  # the teachers' names are checked against the world in main()
        args.social = SocialConfig(**{name: getattr(args, name) for name in SOCIAL_OPTIONS},
                                   teacher_turns=turn_names(args.teacher_turns))
    except ValueError as error:  # its messages start with the setting's name
        p.error(f"--{str(error).replace('_', '-')}")
    kind = learner_kind(args.learner)
    if args.strategies is not None and not kind.chooses_teachers:
        p.error(f"--strategies: {args.learner} takes no strategies, it does not choose its "
                "teachers")
    if args.pond_radius is not None and args.env != "fishing":
        p.error("--pond-radius needs --env fishing")
    refusal = kind.refusal(args.timing, args.demonstration_content)
    if refusal:
        p.error(refusal)
    return args


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    from tqdm import tqdm

    options: dict[str, Any] = {"arm_joints": args.arm_joints} if args.env == "planar-arm" else {}
    if args.pond_radius is not None:
        options["pond_radius"] = args.pond_radius
    try:
        world = build_world(args.env, args.seed, args.noise, **options)
    except WorldMissing as e:  # a world of another package, not installed (core/worlds.py)
        print(f"error: {e}", file=sys.stderr)
        return 2
    except ImportError as e:  # one the world imports
        print(f"error: --env {args.env} needs {e.name}: {e}", file=sys.stderr)
        return 2
    config = LearnerConfig()
    if learner_kind(args.learner).chooses_teachers:  # they answer: core/acts_runner.py
        from .acts_runner import main_acts

        return main_acts(args, world, config)
    learner = make_learner(args.learner, world.env.action_dim, world.env.outcome_dim,
                           args.seed, config, world.scale)
    turns_specs: tuple = ()
    if args.teacher_turns:
        from .teacher_turns import turn_specs

        try:
            turns_specs = turn_specs(args.env, args.teacher_turns)
        except ValueError as error:
            print(f"error: --teacher-turns: {error}", file=sys.stderr)
            return 2
    social = dataclasses.replace(args.social, teacher_turns=turns_specs)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    with args.output.open("w") as f, tqdm(total=args.movements, disable=args.quiet,
                                           desc=args.learner, file=sys.stderr) as bar:
        counts = {"demonstration": 0, "help_request": 0}  # what the teacher showed, asks

        def write(record: dict[str, Any]) -> None:
            if record["type"] in counts:
                counts[record["type"]] += 1
            f.write(json.dumps(record) + "\n")
            f.flush()

        write({"type": "header", "learner": args.learner, "env": args.env, "seed": args.seed,
               "movements": args.movements, "eval_every": args.eval_every,
               "noise": args.noise, **({} if args.pond_radius is None
                                       else {"pond_radius": args.pond_radius}),
               "action_dim": world.env.action_dim,
               "outcome_dim": world.env.outcome_dim, "n_goals": len(world.goals),
               "scale": {"low": list(world.scale.low), "high": list(world.scale.high),
                         "noise": world.scale.noise},
               "teacher": {"period": args.demonstration_period, "rule": args.reached_rule,
                           "choice": args.teacher_choice,
                           "content": args.demonstration_content, "timing": args.timing,
                           "tolerance_noise": args.tolerance_noise,
                           **({"turns": [s.name for s in turns_specs]} if turns_specs
                              else {})},
               "config": config.to_dict()})
        means = run(learner, world, args.movements, args.eval_every, args.seed, write,
                    social, progress=bar.update)
        demos = counts["demonstration"]  # goal- or means-only ones are not in memory
        turns = ((counts["help_request"] if args.timing == ON_REQUEST else
                  budget_for(args.movements, args.demonstration_period))
                 if learner.social else 0)
        write({"type": "end", "final_mean_distance": means[-1], "n_memory": len(learner.memory),
               "n_demonstrations": demos, "n_teacher_turns": turns,
               "n_failures": learner.n_failures, "elapsed_s": time.perf_counter() - start})
    if not args.quiet:
        taught = (f"{demos} demonstrations in {turns} teacher turns ({args.reached_rule} rule, "
                  f"{args.timing})"
                  if learner.social else "no teacher")
        print(f"{args.learner}: final mean distance {means[-1]:.4f}, {taught} "
              f"-> {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
