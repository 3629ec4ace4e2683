"""Probes of the fishing world's physics, with no learner: is it learnable, and how noisy?

The world must pose the paper's problem (redundant, noisy) yet stay learnable: a small change
of an action must move the landing point a little, and the time step must not decide where
it lands. And its motor noise must match the paper's rig (Nguyen et al. 2011 measured 0.073
with their protocol). Each probe returns plain numbers in normalised outcome units; the
`world` experiment's report (experiments/reports/world.py) turns them into a page's figures.

Every touch-down counts, on water or on land: the physics does not care where the hook comes
down, and the noise is that of the rig (motor commands -> touch-down point).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

DELTA = 1e-3
"""The nudge of one action number in the sensitivity probe."""


def _touch_downs(world, actions: Iterable[np.ndarray]) -> np.ndarray:
    """Normalised touch-down points (n, 2); NaN rows for casts that never came down."""
    from sim_bridge.scaling import world_to_outcome

    rows = []
    for action in actions:
        result = world.execute(action)
        rows.append(world_to_outcome(result.world_point) if result.world_point is not None
                    else (np.nan, np.nan))
    return np.asarray(rows, float).reshape(-1, 2)


def _random_actions(seed: int, count: int) -> np.ndarray:
    from sim_bridge.scaling import ACTION_DIM

    return np.random.default_rng(seed).uniform(-1.0, 1.0, (count, ACTION_DIM))


def sensitivity(seed: int, actions: int) -> np.ndarray:
    """How far the landing moves when one action number moves by DELTA, noise off: one shift
    per (action, number) pair whose two casts came down."""
    from sim_bridge.fishing_world import FishingWorld

    shifts = []
    with FishingWorld(seed=seed, noise=0.0) as world:
        for action in _random_actions(seed, actions):
            base = _touch_downs(world, [action])[0]
            nudged = np.repeat(action[None], len(action), axis=0)
            index = np.arange(len(action))
            step = np.where(action + DELTA <= 1.0, DELTA, -DELTA)
            nudged[index, index] += step
            shifts.extend(np.linalg.norm(_touch_downs(world, nudged) - base, axis=1))
    found = np.asarray(shifts, float)
    return found[np.isfinite(found)]


def time_step(seed: int, actions: int) -> np.ndarray:
    """How far the landing moves when the time step halves (1/240 -> 1/480 s), noise off."""
    from sim_bridge.fishing_world import DEFAULT_TIME_STEP, FishingWorld

    chosen = _random_actions(seed, actions)
    landed = []
    for step in (DEFAULT_TIME_STEP, DEFAULT_TIME_STEP / 2):
        with FishingWorld(seed=seed, noise=0.0, time_step=step) as world:
            landed.append(_touch_downs(world, chosen))
    shifts = np.linalg.norm(landed[0] - landed[1], axis=1)
    return shifts[np.isfinite(shifts)]


def paper_noise(seed: int, actions: int, attempts: int) -> np.ndarray:
    """The paper's protocol at the world's own noise: each of `actions` random actions cast
    `attempts` times; its spread is the mean distance of the touch-downs to their mean. One
    spread per action that came down at least twice (their mean is the paper's figure)."""
    from sim_bridge.fishing_world import FishingWorld

    spreads = []
    with FishingWorld(seed=seed) as world:
        for action in _random_actions(seed + 1, actions):
            points = _touch_downs(world, [action] * attempts)
            points = points[np.isfinite(points[:, 0])]
            if len(points) >= 2:
                spreads.append(np.mean(np.linalg.norm(points - points.mean(axis=0), axis=1)))
    return np.asarray(spreads, float)


PROBES = {"sensitivity": sensitivity, "time_step": time_step, "noise": paper_noise}
