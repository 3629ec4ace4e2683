"""The fishing world as the learner core's ``World`` (sgim_nodes.core.worlds), for the
single-process runner's ``--env fishing``.

Here, not in the core, so that the core imports no world package: setup.py registers
``fishing_world`` as the entry point ``fishing`` of the group ``sgim_nodes.worlds``, and the
core's PROVIDERS names it too for a source tree without installed metadata. Only the core loads
this module, so the core is there when it runs; package.xml leaves that dependency implicit
(sgim_nodes depends on this package, not the other way round).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sgim_nodes.core.scale import WorldScale, unit_box
from sgim_nodes.core.worlds import World, evaluation_seed, teacher_seed
from sim_bridge import scaling
from sim_bridge.data_files import load_benchmark_goals, load_teaching_set
from sim_bridge.fishing_world import FishingWorld
from sim_bridge.lake import lake_with_pond_radius


def fishing_scale() -> WorldScale:
    """The fishing world's outcome box and its measured noise (scaling.py)."""
    return unit_box(scaling.OUTCOME_DIM, scaling.OUTCOME_NOISE)


def fishing_world(seed: int, noise: float | None = None,
                  pond_radius: float | None = None) -> World:
    """Training world, a separate evaluation world, benchmark goals and the teaching set.

    ``pond_radius`` (metres): a world whose isolated pond is smaller (``lake.Lake``); None
    keeps the world's default. Its benchmark and teaching sets are read from the data
    directory as usual (point SIM_BRIDGE_DATA_DIR at sets built for it).
    """
    kw: dict[str, Any] = {} if noise is None else {"noise": noise}
    lake = lake_with_pond_radius(pond_radius)
    if pond_radius is not None:
        kw["lake"] = lake
    teacher = teacher_seed(seed)
    ts = load_teaching_set()
    eval_world = FishingWorld(seed=evaluation_seed(seed), **kw)
    return World(FishingWorld(seed=seed, **kw), eval_world,
                 np.asarray(load_benchmark_goals(), dtype=float),
                 np.asarray(ts.actions, dtype=float), np.asarray(ts.outcomes, dtype=float),
                 fishing_scale(), lambda: FishingWorld(seed=teacher, **kw),
                 lake.part_of_outcome)
