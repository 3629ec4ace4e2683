"""Casts whose noise is fixed by what they measure, so that none is made twice.

The evaluator casts the inverse model's action for each benchmark goal every few hundred
movements, and the teacher casts it for each teaching goal at every turn, each in a world of
its own. Late in a run most answers have not changed since the last time: the same action for
the same goal. With the world's noise drawn from one running stream, that cast had to be made
again (its noise was another draw). Here the noise of a cast is drawn from a seed of its own,
made of the world's seed and the cast's key (the goal), so the same action for the same goal
lands at the same point: the cast is made once and its result kept. A world without
``reseed`` (an Environment of the user's) is cast as it is, every time.

What changes for the measurement: each goal keeps its noise draw from one evaluation to the
next (common random numbers), so two evaluations differ only where the learner's answers
differ; each evaluation is still one noisy cast per goal, as before.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from .environment import Environment


class RepeatableCasts:
    """``execute(key, action)``: the world's cast of ``action`` with the noise of ``key``."""

    def __init__(self, world: Environment, seed: int | None = None) -> None:
        self.world = world
        self.base = int(seed if seed is not None else getattr(world, "seed", 0))
        self.repeatable = callable(getattr(world, "reseed", None))
        self._last: dict[bytes, tuple[bytes, Any]] = {}
        self.made = 0
        self.saved = 0

    def _seed(self, key: bytes) -> int:
        digest = hashlib.sha256(key).digest()
        words = [self.base & 0xFFFFFFFF, self.base >> 32 & 0xFFFFFFFF,
                 *np.frombuffer(digest[:16], dtype="<u4").tolist()]
        return int(np.random.SeedSequence(words).generate_state(1, dtype=np.uint64)[0])

    def execute(self, key: bytes, action: np.ndarray) -> Any:
        action = np.asarray(action, dtype=float)
        if not self.repeatable:
            self.made += 1
            return self.world.execute(action)
        code = action.tobytes()
        kept = self._last.get(key)
        if kept is not None and kept[0] == code:
            self.saved += 1
            return kept[1]
        self.world.reseed(self._seed(key))
        result = self.world.execute(action)
        self._last[key] = (code, result)
        self.made += 1
        return result


def goal_key(goal: np.ndarray) -> bytes:
    """A goal's key: its coordinates' bytes."""
    return np.asarray(goal, dtype="<f8").tobytes()
