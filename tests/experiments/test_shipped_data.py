"""The data the repository ships is what today's code makes: for every experiment that ships
some, one of its runs (or result files) is made again for its first movements and compared,
movement for movement (experiments/verify.py, `reproduce.sh NAME --verify`)."""

from __future__ import annotations

import pytest

from sgim_nodes.experiments import pinned, shipped, verify
from sgim_nodes.experiments.runner_jobs import RunnerJob
from sgim_nodes.experiments.world_jobs import CastChunk

FIRST = 160
"""Movements made again (casts, for a world's chunk): past the first teacher's turn."""
EVALUATIONS = 3
"""A runner job's evaluations compared (its result holds no movements): the start's and two
after learning."""


@pytest.mark.parametrize("name", [e.name for e in pinned.all_experiments()])
def test_one_shipped_run_of_each_experiment_is_made_again_the_same(name):
    experiment = pinned.find(name)
    said: list[str] = []
    if experiment.maker == "graph":
        if not shipped.todays_tables(experiment):
            pytest.skip(f"{name} ships no run of today's code")
        found = verify.verify(experiment, 1, 0, False, said.append, movements=FIRST)
    else:
        # Jobs that can be made shorter (a world's probes are made whole only).
        jobs = {job.name: job for job in shipped.file_jobs(experiment)[0]}
        names = sorted(n for n in shipped.shipped_names(experiment)
                       if isinstance(jobs.get(n), RunnerJob | CastChunk))
        if not names:
            pytest.skip(f"{name} ships no result of today's code that can be made shorter")
        chosen = verify.draw(names, 1, 0)
        job = jobs[chosen[0]]
        movements = ((EVALUATIONS - 1) * job.eval_every + 1 if isinstance(job, RunnerJob)
                     else FIRST)
        found = verify.verify_results(experiment, chosen, said.append, movements=movements)
    assert len(found) == 1, said
    assert found[0].same, said
