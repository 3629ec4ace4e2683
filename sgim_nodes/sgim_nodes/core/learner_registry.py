"""Every learner, declared once with its traits: what it is called and drawn as, whether it
takes demonstrations and of what kind, whether it chooses goals, and how the node graph hosts
it. The runner, the graph's description and arbiter, the launch file, the analysis and the
reports read these declarations; no other module names a learner.

A learner of another package registers itself when its module is imported: name the module
in the ``SGIM_LEARNER_MODULES`` environment variable (comma-separated), which every process of
a run inherits, or as an entry point of the group ``sgim_nodes.learners`` (the guide's
"Extending it").
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, Any

from .help_request import ON_REQUEST
from .teaching import GOAL_ONLY, MEANS_AND_GOAL, MEANS_ONLY

if TYPE_CHECKING:  # the learners import this module; their classes are built lazily
    from .learner_base import Learner

MODULES_VARIABLE = "SGIM_LEARNER_MODULES"
ENTRY_POINT_GROUP = "sgim_nodes.learners"

# How the node graph runs a learner (graph/description.py, nodes/social_interaction.py).
GOAL_BABBLING = "goal-babbling"
"""Goal attempts are the explorer's reach_goal jobs, goals from the goal generator, interest
from the interest computer; demonstrations are registered and imitated by their nodes."""
EPISODES = "episodes"
"""As goal babbling, each goal with a strategy; a social one asks a teacher (SGIM-ACTS)."""
IN_ARBITER = "in-arbiter"
"""The arbiter drives the core learner itself, movement by movement, through the simulator:
the same object as the runner's, so the two hosts cannot differ."""
HOSTS = (GOAL_BABBLING, EPISODES, IN_ARBITER)

Builder = Callable[..., "Learner"]
"""(action_dim, outcome_dim, seed, config, scale, teachers, strategies) -> Learner."""


@dataclass(frozen=True)
class LearnerKind:
    """One learner's declaration."""

    name: str
    display: str
    """Its name in figures, tables and the web page."""
    colour: str | None
    """Its colour in every figure (a matplotlib colour); None: one of the spare colours."""
    build: Builder
    summary: str
    """One line for --help and the reference."""
    host: str = IN_ARBITER
    social: bool = False
    """It takes the teacher's demonstrations at the teacher's turns."""
    contents: tuple[str, ...] = ()
    """What a demonstration may show it (core/teaching.py); empty when it takes none."""
    asks: bool = False
    """It may ask for help when its progress stalls (timing on-request, help_request.py)."""
    chooses_teachers: bool = False
    """It asks teachers of its own, with a strategy per episode (SGIM-ACTS)."""
    compared: bool = True
    """Among the paper's learners and yardsticks that the studies compare."""
    goal_modes: tuple[float, float, float] | None = None
    """SAGG-RIAC's goal modes when not the configured ones (random goals: mode 2 only)."""
    own_modules: tuple[str, ...] = ()
    """Core modules only this learner's runs go through (provenance/fingerprint.py)."""

    def __post_init__(self) -> None:
        if self.host not in HOSTS:
            raise ValueError(f"learner {self.name!r}: host must be one of {HOSTS}")
        if self.social != bool(self.contents):
            raise ValueError(f"learner {self.name!r}: a social learner names the "
                             "demonstration contents it takes, and only a social one does")

    @property
    def goal_babbling(self) -> bool:
        """It chooses goals (region tree, goal generator, explorer)."""
        return self.host in (GOAL_BABBLING, EPISODES)

    @property
    def imitates(self) -> bool:
        """The graph's imitation node serves it."""
        return self.goal_babbling and (self.social or self.chooses_teachers)

    def refusal(self, timing: str | None = None, content: str | None = None) -> str:
        """Why this learner cannot play a social mode (timing, demonstration content), or ''.
        One rule for the runner, the graph's description and the arbiter."""
        if timing == ON_REQUEST and self.social and not self.asks:
            asking = ", ".join(k.name for k in kinds() if k.asks)
            return (f"{self.name} attempts no goals, so it never asks: timing on-request "
                    f"needs a learner that asks ({asking})")
        if content is not None and self.social and content not in self.contents:
            return (f"{self.name} cannot learn from a {content} demonstration: it takes "
                    f"{' or '.join(self.contents)}")
        return ""


_KINDS: dict[str, LearnerKind] = {}
_loaded = False


def register(kind: LearnerKind) -> LearnerKind:
    """Declare a learner (a later declaration of the same name replaces it)."""
    _KINDS[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Forget a declaration (a test's learner, once the test is done)."""
    _KINDS.pop(name, None)


def _load_plugins() -> None:
    """Import the learners of other packages once (module docstring)."""
    global _loaded
    if _loaded:
        return
    _loaded = True
    for point in entry_points(group=ENTRY_POINT_GROUP):
        point.load()
    for module in filter(None, (m.strip() for m in os.environ.get(MODULES_VARIABLE,
                                                                   "").split(","))):
        try:
            importlib.import_module(module)
        except ImportError as error:  # the learner is then unknown, and refused by name
            print(f"warning: {MODULES_VARIABLE} names {module!r}, which cannot be imported "
                  f"({error}): its learners are unknown", file=sys.stderr)


def kinds(plugins: bool = True) -> tuple[LearnerKind, ...]:
    """Every learner, the paper's first, in their order of declaration; without
    ``plugins``, only those already declared (no other package is looked for: what a module
    reads when it is imported, so that no process pays for the search it does not need)."""
    if plugins:
        _load_plugins()
    return tuple(_KINDS.values())


def learner_names(plugins: bool = True) -> tuple[str, ...]:
    """Every learner the runner builds and the graph runs."""
    return tuple(k.name for k in kinds(plugins))


def compared_names(plugins: bool = True) -> tuple[str, ...]:
    """The paper's learners and its yardsticks, in the studies' order."""
    return tuple(k.name for k in kinds(plugins) if k.compared)


def learner_kind(name: str) -> LearnerKind:
    """The declaration of learner ``name`` (other packages are looked for only when it is not
    one of the declared ones); ValueError naming the known ones."""
    if name not in _KINDS:
        _load_plugins()
    if name not in _KINDS:
        raise ValueError(f"unknown learner {name!r}; choose one of {', '.join(_KINDS)}")
    return _KINDS[name]


def is_learner(name: Any) -> bool:
    """Whether ``name`` names a declared learner."""
    try:
        learner_kind(str(name))
    except ValueError:
        return False
    return True


def goal_mode_probabilities(config: Any, learner: str) -> tuple[float, float, float]:
    """SAGG-RIAC's three modes (the config's), unless the learner declares its own."""
    own = learner_kind(learner).goal_modes
    return own if own is not None else (config.p_mode1, config.p_mode2, config.p_mode3)


def display_name(name: str) -> str:
    """A learner's name in figures and pages; an unknown one as it is written."""
    return learner_kind(name).display if is_learner(name) else name


def colour(name: str) -> str | None:
    """A learner's colour in figures; None for an unknown one or one without its own."""
    return learner_kind(name).colour if is_learner(name) else None


def make_learner(name: str, action_dim: int, outcome_dim: int, seed: int,
                 config: Any = None, scale: Any = None, teachers: Sequence[str] = (),
                 strategies: Sequence[str] | None = None) -> Learner:
    """Build learner ``name``; ``seed`` fixes every random stream (random_streams.py),
    ``scale`` is the world's (scale.py). Only a learner that chooses its teachers takes
    ``teachers`` and ``strategies`` (names; default: every one)."""
    kind = learner_kind(name)
    if not kind.chooses_teachers and (tuple(teachers) or strategies is not None):
        choosers = ", ".join(k.name for k in kinds() if k.chooses_teachers)
        raise ValueError(f"{name} takes no teachers or strategies: only {choosers} "
                         "chooses them")
    return kind.build(action_dim, outcome_dim, seed, config, scale, teachers, strategies)


# --- the paper's learners, its yardsticks and SGIM-ACTS ------------------------------------

def _named(learner: Learner, name: str) -> Learner:
    learner.name = name
    return learner


def _goal_babbler(name: str, social: bool, goal_modes=None) -> Builder:
    def build(action_dim, outcome_dim, seed, config, scale, teachers, strategies):
        from .learners import GoalBabblingLearner

        return _named(GoalBabblingLearner(action_dim, outcome_dim, seed, config, scale,
                                          social=social, goal_modes=goal_modes), name)
    return build


def _demo_only(action_dim, outcome_dim, seed, config, scale, teachers, strategies):
    from .learners import DemoOnlyLearner

    return _named(DemoOnlyLearner(action_dim, outcome_dim, seed, config, scale), DEMO_ONLY)


def _random(action_dim, outcome_dim, seed, config, scale, teachers, strategies):
    from .learners import RandomLearner

    return _named(RandomLearner(action_dim, outcome_dim, seed, config, scale), RANDOM)


def _acts(action_dim, outcome_dim, seed, config, scale, teachers, strategies):
    from .acts_learner import SgimActsLearner
    from .strategies import parse_strategies

    chosen = None if strategies is None else parse_strategies(strategies, config, teachers)
    return _named(SgimActsLearner(action_dim, outcome_dim, seed, config, scale, teachers,
                                  chosen), SGIM_ACTS)


ALL_CONTENTS = (MEANS_AND_GOAL, GOAL_ONLY, MEANS_ONLY)
SGIM_D, SAGGRIAC, RANDOM_GOALS, DEMO_ONLY, RANDOM, SGIM_ACTS = (
    "sgim-d", "saggriac", "random-goals", "demo-only", "random", "sgim-acts")
UNIFORM_GOALS = (0.0, 1.0, 0.0)

register(LearnerKind(
    SGIM_D, "SGIM-D", "tab:red", _goal_babbler(SGIM_D, social=True),
    "SAGG-RIAC goal babbling that stores, imitates and learns the interest of each "
    "demonstration (the paper's)", host=GOAL_BABBLING, social=True, contents=ALL_CONTENTS,
    asks=True))
register(LearnerKind(
    SAGGRIAC, "SAGG-RIAC", "tab:blue", _goal_babbler(SAGGRIAC, social=False),
    "SAGG-RIAC goal babbling; no teacher", host=GOAL_BABBLING))
register(LearnerKind(
    RANDOM_GOALS, "random goals", "tab:purple",
    _goal_babbler(RANDOM_GOALS, social=False, goal_modes=UNIFORM_GOALS),
    "goals uniform in the outcome box, the same lower level (SAGG-Random)",
    host=GOAL_BABBLING, goal_modes=UNIFORM_GOALS))
register(LearnerKind(
    DEMO_ONLY, "demonstrations only", "tab:green", _demo_only,
    "small variations of the latest demonstration", social=True,
    contents=(MEANS_AND_GOAL, MEANS_ONLY)))
register(LearnerKind(RANDOM, "random actions", "tab:gray", _random, "uniform random actions"))
register(LearnerKind(
    SGIM_ACTS, "SGIM-ACTS", None, _acts,
    "chooses for each episode a goal region and a strategy, asking teachers of its own",
    host=EPISODES, chooses_teachers=True, compared=False,
    own_modules=("acts_episode", "acts_learner", "acts_runner", "experts", "strategies",
                 "strategy_choice", "strategy_regions", "teacher_turns")))

OWN_NAMES = tuple(_KINDS)
"""The learners this project declares (the others come from other packages)."""
