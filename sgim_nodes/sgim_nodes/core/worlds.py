"""The worlds the runner learns in, by name, behind one interface: a factory that builds a
``World`` (the training, evaluation and teacher's environments, benchmark goals, teaching set).

Why a registry: the core imports no world package. The analytic arms (planar_arm.py) are
registered here. A world of another package names its factory as a Python entry point of the
group ``sgim_nodes.worlds`` in its setup.py (sim_bridge's fishing world: ``fishing =
sim_bridge.core_world:fishing_world``), which pip and colcon install as metadata. A source tree
run on pyproject's pythonpath has no installed metadata, so ``PROVIDERS`` names the known ones
again, as data (the same entry point values); an installed entry point of the same name wins.
A factory is loaded when a run first asks for its world.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import Any

import numpy as np

from .environment import Environment
from .evaluator import EVALUATION_SEED_OFFSET
from .planar_arm import ARMS, PlanarArm, benchmark_goals, teaching_set
from .random_streams import world_seed
from .scale import WorldScale

ENTRY_POINT_GROUP = "sgim_nodes.worlds"


@dataclass
class World:
    env: Environment
    eval_env: Environment
    goals: np.ndarray
    teaching_actions: np.ndarray | None
    teaching_outcomes: np.ndarray | None
    scale: WorldScale
    # The teacher's own copy of the world (teaching.py, rule "ability"), built on demand:
    # only a social learner's teacher casts in it.
    make_teacher_env: Callable[[], Environment] | None = None
    # The named part of the world an outcome lies in (the fishing lake's basin, arms and
    # pond), for teachers who know some parts only (experts.py); None: the world names none.
    part_of: Callable[[np.ndarray], str] | None = None


WorldFactory = Callable[..., World]
"""``factory(seed, noise, **options)``: the world of a run of ``seed`` (its evaluation and
teacher's copies seeded by evaluation_seed and teacher_seed), ``noise`` None for the world's
own; ``options`` are the world's own keywords (planar-arm: arm_joints, arm_cells)."""


@dataclass(frozen=True)
class Provider:
    """A world of another package: its factory as an entry point value, and how to get it."""

    factory: str  # "module:attribute"
    package: str
    install: str


PROVIDERS = {"fishing": Provider("sim_bridge.core_world:fishing_world", "sim_bridge",
                                 "pip install ./sim_bridge")}
"""The worlds of other packages the core knows of without their metadata (module docstring):
module names as data, imported only when a run asks for the world."""

_FACTORIES: dict[str, WorldFactory] = {}


class WorldMissing(ImportError):
    """A known world whose package is not installed; the message says what to install."""


def register_world(name: str, factory: WorldFactory) -> None:
    """Make ``build_world(name, ...)`` call ``factory`` (a later registration replaces it)."""
    _FACTORIES[name] = factory


def world_names() -> tuple[str, ...]:
    """Every world build_world knows, installed or not (a missing one says what it needs)."""
    installed = (point.name for point in entry_points(group=ENTRY_POINT_GROUP))
    return tuple(dict.fromkeys([*PROVIDERS, *_FACTORIES, *installed]))


def world_factory(name: str) -> WorldFactory:
    """The factory of world ``name``: registered, else loaded from its entry point."""
    if name in _FACTORIES:
        return _FACTORIES[name]
    point = next(iter(entry_points(group=ENTRY_POINT_GROUP, name=name)), None)
    if point is None and name in PROVIDERS:
        point = EntryPoint(name, PROVIDERS[name].factory, ENTRY_POINT_GROUP)
    if point is None:
        raise ValueError(f"unknown env {name!r}; choose one of {world_names()}")
    try:
        factory = point.load()
    except ModuleNotFoundError as e:
        # The provider's own module or a package above it is missing (not one it imports).
        if e.name is None or not f"{point.module}.".startswith(f"{e.name}."):
            raise
        known = PROVIDERS.get(name)
        needs = f"{known.package} ({known.install})" if known else point.module.split(".")[0]
        raise WorldMissing(f"the {name} world needs {needs}", name=e.name) from None
    register_world(name, factory)
    return factory


def build_world(name: str, seed: int, noise: float | None = None, **options: Any) -> World:
    """World ``name`` for a run of ``seed``; ``noise`` None keeps the world's own; ``options``
    are the world's own keywords (a keyword it does not take is an error, not ignored)."""
    factory = world_factory(name)
    parameters = inspect.signature(factory).parameters
    if not any(p.kind is p.VAR_KEYWORD for p in parameters.values()):
        own = sorted(set(parameters) - {"seed", "noise"})
        unknown = sorted(set(options) - set(own))
        if unknown:
            raise ValueError(f"world {name!r} takes no {', '.join(unknown)} (its options: "
                             f"{', '.join(own) or 'none'})")
    return factory(seed, noise, **options)


def evaluation_seed(seed: int) -> int:
    """The seed of a run's evaluation world, so that its noise stream is independent."""
    return seed + EVALUATION_SEED_OFFSET


def teacher_seed(seed: int) -> int:
    """The seed of the teacher's own copy of a run's world (teaching.py, rule "ability")."""
    return world_seed(seed, "teacher-world")


def _arm_world(make: Callable[[int], Environment], seed: int,
               cells: int | tuple[int, int]) -> World:
    teacher = teacher_seed(seed)
    env, eval_env = make(seed), make(evaluation_seed(seed))
    ts = teaching_set(env, cells=cells)
    return World(env, eval_env, benchmark_goals(env, cells=cells), ts.actions, ts.outcomes,
                 env.scale, lambda: make(teacher))


def planar_arm_world(seed: int, noise: float | None = None, arm_joints: int = 12,
                     arm_cells: int = 12) -> World:
    """The small test arm: ``arm_joints`` joints, noise-free by default."""
    kw = {} if noise is None else {"noise": noise}
    return _arm_world(lambda at: PlanarArm(n_joints=arm_joints, seed=at, **kw), seed,
                      arm_cells)


def benchmark_arm_world(name: str) -> WorldFactory:
    """The factory of a benchmark arm of planar_arm.ARMS."""
    spec = ARMS[name]

    def build(seed: int, noise: float | None = None) -> World:
        return _arm_world(lambda at: spec.make(at, noise), seed, spec.cells)

    return build


register_world("planar-arm", planar_arm_world)
for _name in ARMS:
    register_world(_name, benchmark_arm_world(_name))
