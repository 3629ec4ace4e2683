"""The parts every learner shares: the base class with its memory and inverse model, and the
SAGG-RIAC region tree they build.

Kept apart from learners.py so that SGIM-ACTS (acts_learner.py) builds on them while
learners.make_learner builds SGIM-ACTS, with no import circle between the two modules.
"""

from __future__ import annotations

import numpy as np

from .config import LearnerConfig
from .environment import ResultLike, is_success
from .inverse_model import InverseModel
from .memory import Memory
from .random_streams import RandomStreams
from .region_tree import RegionTree
from .scale import WorldScale
from .teaching import OWN_PROCESSES

DEMONSTRATION = "demonstration"


def build_memory(config: LearnerConfig, action_dim: int, outcome_dim: int,
                 scale: WorldScale) -> tuple[Memory, InverseModel]:
    """The (action, outcome) memory and the inverse model over it, as every learner has them
    (the graph's explorer and evaluator build theirs with this too)."""
    c = config
    memory = Memory(action_dim, outcome_dim, c.memory_rebuild_fraction, c.memory_min_tail,
                    c.memory_max_tail)
    return memory, inverse_model_for(memory, config, scale)


def inverse_model_for(memory: Memory, config: LearnerConfig, scale: WorldScale) -> InverseModel:
    """The configured inverse model over ``memory``; the world's scale gives it the noise
    its step check compares with."""
    c = config
    radius = c.local_radius_action * float(np.sqrt(memory.action_dim))
    noise = scale.noise_rms if c.local_step_check == "held-out" else None
    return InverseModel(memory, c.inverse_model, c.l_max, c.k_max, c.alpha, radius,
                        c.local_neighbours, c.local_step_fraction * radius,
                        c.local_min_casts, noise, c.local_rank_min_casts,
                        c.local_step_support)


def region_tree_for(config: LearnerConfig, scale: WorldScale) -> RegionTree:
    """The SAGG-RIAC region tree over the world's outcome box."""
    c = config
    return RegionTree(scale.low_array, scale.high_array, c.max_goals_per_region, c.zeta,
                      c.min_goals_per_child, c.distances(scale).min_region_width,
                      c.interest_noise_correction, c.region_split)


def inverse_or_centre(model: InverseModel, goal: np.ndarray, action_dim: int) -> np.ndarray:
    """Inverse model's action; the centre of the action space when memory is empty."""
    a = model(goal)
    return np.zeros(action_dim) if a is None else a


class Learner:
    """Common parts: memory, inverse model, movement counter."""

    name = "base"
    social = False

    def __init__(self, action_dim: int, outcome_dim: int, seed: int,
                 config: LearnerConfig | None = None, scale: WorldScale | None = None) -> None:
        self.config = config or LearnerConfig()
        if scale is None:
            raise ValueError("a learner needs the world's scale (outcome box and noise)")
        if scale.dim != outcome_dim:
            raise ValueError(f"world scale has {scale.dim} outcome numbers, not {outcome_dim}")
        self.scale = scale
        self.action_dim = action_dim
        self.outcome_dim = outcome_dim
        self.rngs = RandomStreams.from_seed(seed)
        self.memory, self.inverse_model = build_memory(self.config, action_dim, outcome_dim,
                                                       scale)
        self.n_movements = 0
        self.n_failures = 0

    def next_action(self) -> tuple[np.ndarray, str]:
        raise NotImplementedError

    def aim(self) -> np.ndarray | None:
        """The outcome the latest action aims at, if any: what a movement's record names as
        its goal."""
        return None

    def observe(self, action: np.ndarray, result: ResultLike) -> None:
        self.n_movements += 1
        if is_success(result):
            self.memory.add(np.asarray(action, dtype=float),
                            np.asarray(result.outcome, dtype=float), self._last_label)
        else:
            self.n_failures += 1
        self._after_observe(action, result)

    def _after_observe(self, action: np.ndarray, result: ResultLike) -> None:
        pass

    def on_demonstration(self, action: np.ndarray, outcome: np.ndarray) -> None:
        """Ignored by non-social learners."""

    def on_teacher_turn(self) -> None:
        """The teacher's turn came (every P movements), with or without a demonstration."""

    def inverse(self, goal: np.ndarray) -> np.ndarray:
        return inverse_or_centre(self.inverse_model, goal, self.action_dim)

    def reached_outcomes(self) -> np.ndarray:
        return self.memory.outcomes

    def own_outcomes(self) -> np.ndarray:
        """Outcomes of the learner's own movements (OWN_PROCESSES: not the demonstrations,
        not the imitations): what the teacher judges "reached" on."""
        labels = np.asarray(self.memory.labels)
        return self.memory.outcomes[np.isin(labels, OWN_PROCESSES)]

    _last_label = ""
