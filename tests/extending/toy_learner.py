"""A learner of another package, as the guide's "Adding a learner" recipe makes one: its class
and its declaration, in one module that registers it when imported. A run names the module in
SGIM_LEARNER_MODULES, so that every process of the graph knows the learner.

It draws its actions uniformly in the central half of the action box: enough to tell its
movements from every other learner's, and nothing the core's random actions can make.
"""

from __future__ import annotations

import numpy as np

from sgim_nodes.core.learner_base import Learner
from sgim_nodes.core.learner_registry import LearnerKind, register

TOY = "toy-centre"
HALF_WIDTH = 0.5
LABEL = "random"  # its movements' process: it babbles, as random actions do


class CentreBabbler(Learner):
    def next_action(self) -> tuple[np.ndarray, str]:
        self._last_label = LABEL
        return self.rngs.random.uniform(-HALF_WIDTH, HALF_WIDTH, self.action_dim), LABEL


def build(action_dim, outcome_dim, seed, config, scale, teachers, strategies) -> Learner:
    learner = CentreBabbler(action_dim, outcome_dim, seed, config, scale)
    learner.name = TOY
    return learner


KIND = register(LearnerKind(TOY, "centre babbling", "tab:olive", build,
                            "uniform actions in the central half of the action box",
                            compared=False))
