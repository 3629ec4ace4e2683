"""Small fake worlds for the tests."""

import numpy as np

from sgim_nodes.core.environment import MovementResult, Status


class IdentityWorld:
    """Outcome = the first two action components (clipped): every goal is reachable."""

    def __init__(self, action_dim: int = 2) -> None:
        self.action_dim, self.outcome_dim, self.calls = action_dim, 2, 0

    def execute(self, action):
        self.calls += 1
        return MovementResult(np.clip(np.asarray(action, float)[:2], -1, 1), Status.OK)


class ConstantWorld(IdentityWorld):
    """Always the same outcome."""

    def __init__(self, outcome, action_dim: int = 2) -> None:
        super().__init__(action_dim)
        self.outcome = np.asarray(outcome, float)

    def execute(self, action):
        self.calls += 1
        return MovementResult(self.outcome.copy(), Status.OK)


class FlakyWorld:
    """Wraps a world; every ``every``-th movement fails with PHYSICS_FAILURE."""

    def __init__(self, inner, every: int = 3) -> None:
        self.inner, self.every, self.calls = inner, every, 0
        self.action_dim, self.outcome_dim = inner.action_dim, inner.outcome_dim

    def execute(self, action):
        self.calls += 1
        if self.calls % self.every == 0:
            return MovementResult(None, Status.PHYSICS_FAILURE)
        return self.inner.execute(action)
