"""The teaching set a teacher node shows from, checked against the run's sizes."""

from __future__ import annotations

from sgim_ros.params import ParameterError
from sim_bridge.data_files import load_teaching_set


def load_checked(path: str, action_size: int, outcome_size: int):
    """The teaching set at `path` (empty: the packaged one), or ParameterError when its
    actions or outcomes are not the run's sizes."""
    ts = load_teaching_set(path or None)
    if ts.actions.shape[1] != action_size or ts.outcomes.shape[1] != outcome_size:
        raise ParameterError(f"teaching set of {ts.actions.shape[1]}-number actions and "
                             f"{ts.outcomes.shape[1]}-number outcomes does not fit "
                             f"action_size {action_size}, outcome_size {outcome_size}")
    return ts
