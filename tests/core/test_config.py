"""LearnerConfig: defaults valid, frozen, and every invalid value names its field."""

import dataclasses

import pytest

from sgim_nodes.core.config import LearnerConfig


def test_defaults_are_valid_and_frozen():
    c = LearnerConfig()
    assert c.alpha == 0.5  # the paper's value
    assert abs(c.p_mode1 + c.p_mode2 + c.p_mode3 - 1.0) < 1e-12
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.alpha = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("success_tolerance_noise", {"success_tolerance_noise": -0.1}),
        ("competence_reference", {"competence_reference": "origin"}),
        ("zeta", {"zeta": 7}),
        ("zeta", {"zeta": 60, "max_goals_per_region": 50}),
        ("p_mode1", {"p_mode1": 0.5, "p_mode2": 0.2, "p_mode3": 0.2}),
        ("p_mode2", {"p_mode2": -0.1}),
        ("l_max", {"l_max": 0}),
        ("k_max", {"k_max": 0}),
        ("alpha", {"alpha": -1.0}),
        ("explore_cap", {"explore_cap": 1.5}),
        ("imitation_epsilon", {"imitation_epsilon": 0.0}),
        ("goal_budget", {"goal_budget": 0}),
        ("min_goals_per_child", {"min_goals_per_child": 60}),
        ("inverse_model", {"inverse_model": "average"}),
        ("optimiser", {"optimiser": "bfgs"}),
        ("reach_threshold_noise", {"reach_threshold_noise": 0.0}),
        ("attempt_patience", {"attempt_patience": 0}),
    ],
)
def test_invalid_values_raise_naming_the_field(field, kwargs):
    with pytest.raises(ValueError, match=rf"LearnerConfig\.{field}\b"):
        LearnerConfig(**kwargs)
