"""Movement k gets the k-th noise of the seed's stream: after a restarted simulator, a
re-execution or a cast that is not recorded, the movements are the uninterrupted run's (the
chaos soak's seed 18 found a killed simulator's run going on with other noise)."""

import numpy as np
import pytest

from sim_bridge.fishing_world import FishingWorld
from sim_bridge.noise_cursor import NoiseCursor

SEED = 18


@pytest.fixture(scope="module")
def actions() -> np.ndarray:
    return np.random.default_rng(5).uniform(-1, 1, (6, 24))


def cast(cursor: NoiseCursor, action: np.ndarray, index: int | None) -> tuple:
    result = cursor.execute(action, index)
    return int(result.status), None if result.outcome is None else tuple(result.outcome)


@pytest.fixture(scope="module")
def uninterrupted(actions) -> list[tuple]:
    """Movements 1..6 cast one after another in one world, as the runner casts them."""
    with FishingWorld(seed=SEED) as world:
        results = [world.execute(a) for a in actions]
    return [(int(r.status), None if r.outcome is None else tuple(r.outcome)) for r in results]


def test_an_uninterrupted_run_is_cast_as_without_the_cursor(actions, uninterrupted):
    with FishingWorld(seed=SEED) as world:
        cursor = NoiseCursor(world)
        assert [cast(cursor, a, k) for k, a in enumerate(actions, 1)] == uninterrupted
        assert cursor.casts == len(actions)


def test_a_restarted_simulator_casts_the_next_movement_with_its_own_noise(actions,
                                                                          uninterrupted):
    with FishingWorld(seed=SEED) as restarted:  # killed after movement 3, started again
        cursor = NoiseCursor(restarted)
        assert [cast(cursor, actions[k - 1], k) for k in (4, 5, 6)] == uninterrupted[3:]


def test_a_re_execution_gets_the_noise_of_its_first_attempt(actions, uninterrupted):
    with FishingWorld(seed=SEED) as world:
        cursor = NoiseCursor(world)
        made = [cast(cursor, actions[k - 1], k) for k in (1, 2, 3, 3, 4)]  # 3 executed twice
    assert made == [*uninterrupted[:3], uninterrupted[2], uninterrupted[3]]


def test_a_cast_not_recorded_leaves_the_movements_noise_alone(actions, uninterrupted):
    with FishingWorld(seed=SEED) as world:
        cursor = NoiseCursor(world)
        made = [cast(cursor, actions[0], 1), cast(cursor, actions[1], 2)]
        cast(cursor, actions[5], None)  # a teacher measuring an action: record=false
        made += [cast(cursor, actions[k - 1], k) for k in (3, 4)]
    assert made == uninterrupted[:4]


def test_a_refused_action_draws_no_noise(actions, uninterrupted):
    with FishingWorld(seed=SEED) as world:
        cursor = NoiseCursor(world)
        refused = cast(cursor, np.full(24, 5.0), 1)
        assert refused[1] is None and cursor.casts == 0
        assert [cast(cursor, a, k) for k, a in enumerate(actions[:2], 1)] == uninterrupted[:2]


def test_a_movement_far_ahead_is_refused_at_once_and_draws_nothing(actions, uninterrupted):
    """A forged index (the live-node fuzzer's 40,427,983 held the simulator half a minute per
    request) is answered at once as a bad action; the run's own next movement is unchanged."""
    import time

    from sim_bridge.fishing_world import Status
    from sim_bridge.noise_cursor import MAX_SKIP

    with FishingWorld(seed=SEED) as world:
        cursor = NoiseCursor(world)
        assert [cast(cursor, a, k) for k, a in enumerate(actions[:2], 1)] == uninterrupted[:2]
        start = time.process_time()
        for index in (40_427_983, 2**32 - 1, MAX_SKIP + 4):
            result = cursor.execute(actions[2], index)
            assert result.status == Status.INVALID_ACTION and result.outcome is None
            assert f"movement {index} is" in result.message and "ahead" in result.message
        assert time.process_time() - start < 5  # drawing 40 million casts' noise takes ~30 s
        assert cursor.casts == 2
        assert cast(cursor, actions[2], 3) == uninterrupted[2]
        # Within reach (MAX_SKIP casts ahead of cast 2) is served: a deep restart.
        assert cursor.execute(actions[3], MAX_SKIP + 3).status != Status.INVALID_ACTION
