"""What the arbiter measures of a demonstration's imitation, and how a resumed run finishes an
imitation that a kill cut (bag/resume.py CutImitation).

The competence of an imitation is that of its best outcome against memory's distance to the
demonstrated outcome before the demonstration was stored, as the single-process learner
measures it; a resumed run counts the imitations the killed run made with those it makes.
"""

from __future__ import annotations

import numpy as np

from sgim_msgs.action import Imitate
from sgim_msgs.msg import Competence, Demonstration
from sgim_nodes.bag.resume import (
    CutImitation,
    ResumePoint,
    cut_imitation,
    imitation_start_distance,
)
from sgim_nodes.core import portable
from sgim_nodes.core.competence import start_distance
from sgim_nodes.core.config import Distances, LearnerConfig
from sgim_nodes.nodes.ros_glue import floats, vec


def imitation_competence(distances: Distances, demo: Demonstration,
                         result: Imitate.Result | None, start: float, count: int, stamp,
                         earlier: np.ndarray | None = None,
                         earlier_used: int = 0) -> Competence | None:
    """The competence of a demonstration's imitation ending at movement ``count``
    (``earlier``: the best outcome of the imitations a killed run made, ``earlier_used`` of
    them); None when it made no movement."""
    used = earlier_used + (result.movements_used if result is not None else 0)
    if used == 0:
        return None
    goal = vec(demo.outcome)
    made = vec(result.best_outcome) if result is not None and len(result.best_outcome) else None
    found = [o for o in (earlier, made) if o is not None]
    best = min(found, key=lambda o: portable.norm(o - goal)) if found else None
    return Competence(stamp=stamp, goal_index=0, movement_index=count, goal=floats(goal),
                      reached=[] if best is None else floats(best),
                      competence=distances.competence(goal, best, start), movements_used=used,
                      from_demonstration=True)


def resumed_cut(point: ResumePoint, config: LearnerConfig, budget: int,
                centre: np.ndarray) -> tuple[CutImitation | None, float]:
    """The imitation the resumed run must finish first, and memory's distance to its
    demonstrated outcome before it was stored (as the explorer measured it then)."""
    cut = cut_imitation(point.records, point.count, config.imitation_count, budget)
    if cut is None or not cut.measured:
        return cut, float("inf")
    outcome = vec(cut.demonstration.outcome)
    closest = imitation_start_distance(point.records, cut.demonstration, config)
    return cut, start_distance(closest, outcome, centre)


def as_message(cut: CutImitation) -> Demonstration:
    """The cut imitation's demonstration, as the arbiter took it."""
    d = cut.demonstration
    return Demonstration(index=d.index, movement_index=d.movement_index,
                         action=floats(d.action), outcome=floats(d.outcome),
                         teaching_set_index=d.teaching_set_index, source=d.source,
                         content=d.content, help_request=d.help_request)
