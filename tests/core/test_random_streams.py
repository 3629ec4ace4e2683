"""Per-component random streams: reproducible in any process, independent of each other."""

import numpy as np
import pytest

from sgim_nodes.core.learner_registry import make_learner
from sgim_nodes.core.random_streams import STREAM_NAMES, component_rng
from sgim_nodes.core.scale import unit_box


def test_same_seed_and_name_give_the_same_numbers_anywhere():
    a = component_rng(7, "goals").random(5)
    b = component_rng(7, "goals").random(5)
    assert np.array_equal(a, b)


def test_streams_differ_by_name_and_by_seed():
    draws = {name: component_rng(7, name).random(4).tobytes() for name in STREAM_NAMES}
    assert len(set(draws.values())) == len(STREAM_NAMES)
    assert not np.array_equal(
        component_rng(7, "goals").random(4), component_rng(8, "goals").random(4)
    )


def test_the_random_learner_draws_from_its_named_stream():
    learner = make_learner("random", 24, 2, seed=11, scale=unit_box(2, 0.07))
    expected = component_rng(11, "random").uniform(-1.0, 1.0, (3, 24))
    for row in expected:
        action, label = learner.next_action()
        assert label == "random" and np.array_equal(action, row)


@pytest.mark.parametrize(("seed", "name"), [(-1, "goals"), (0, "nonsense")])
def test_bad_stream_requests_are_refused(seed, name):
    with pytest.raises(ValueError):
        component_rng(seed, name)
