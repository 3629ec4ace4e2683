"""The guide's "Adding a learner" recipe, as a test: a learner declared in a module of its
own (toy_learner.py) runs through the runner and through the graph, movement for movement the
same, with no other file of the project touched."""

from __future__ import annotations

import os
import subprocess

import numpy as np
import pytest

from sgim_nodes.core.learner_registry import (
    MODULES_VARIABLE,
    is_learner,
    learner_kind,
    learner_names,
    register,
    unregister,
)
from tests.conftest import REPO
from tests.golden_runs import SEED, bag_digest, runner_digest, runner_records

MODULE = "tests.extending.toy_learner"
MOVEMENTS = 30


@pytest.fixture
def toy_learner():
    """The toy module, its learner declared during the test only: the other tests of this
    process see the project's learners alone."""
    from tests.extending import toy_learner as module  # declares it when first imported

    register(module.KIND)  # again, when another test of this process imported it first
    yield module
    unregister(module.TOY)


def test_a_registered_learner_is_known_everywhere_a_learner_is_named(toy_learner):
    from sgim_nodes.graph.description import RunOptions, graph

    assert toy_learner.TOY in learner_names()
    kind = learner_kind(toy_learner.TOY)
    assert (kind.social, kind.goal_babbling, kind.compared) == (False, False, False)
    # The graph hosts it in the arbiter: no explorer, goal generator or imitation node.
    nodes = [spec.executable for spec in graph(toy_learner.TOY, markers=False)]
    assert nodes == ["recorder", "sim_bridge", "evaluator", "social_interaction"]
    assert RunOptions(toy_learner.TOY).learner == toy_learner.TOY  # the launcher takes it
    assert is_learner(toy_learner.TOY)  # and every node's `learner` parameter


def test_a_forgotten_learner_is_refused(toy_learner):
    unregister(toy_learner.TOY)
    assert not is_learner(toy_learner.TOY)
    with pytest.raises(ValueError, match="unknown learner 'toy-centre'"):
        learner_kind(toy_learner.TOY)


def test_the_runner_runs_it(toy_learner):
    records = runner_records(toy_learner.TOY, movements=MOVEMENTS, eval_every=0)
    moves = [r for r in records if r["type"] == "movement"]
    assert len(moves) == MOVEMENTS
    actions = np.array([m["action"] for m in moves])
    assert np.all(np.abs(actions) <= toy_learner.HALF_WIDTH)
    assert len({tuple(a) for a in actions}) == MOVEMENTS


def test_a_name_no_module_declares_is_refused_with_the_known_ones(toy_learner):
    with pytest.raises(ValueError, match=f"unknown learner 'nobody'.*{toy_learner.TOY}"):
        learner_kind("nobody")


@pytest.mark.ros
def test_the_graph_runs_it_as_the_runner_does(ros_processes, ros_domain, tmp_path,
                                               toy_learner):
    from sgim_nodes.bag.reader import load_run

    ros_processes.env = {**(ros_processes.env or os.environ), MODULES_VARIABLE: MODULE,
                         "PYTHONPATH": os.pathsep.join(
                             [str(REPO), (ros_processes.env or os.environ).get("PYTHONPATH",
                                                                               "")])}
    child = ros_processes.start(
        "run-toy", [str(REPO / "ros_ws" / "run_experiment.sh"), toy_learner.TOY, "--seed",
                    str(SEED), "--movements", str(MOVEMENTS), "--eval-every", "0",
                    "--runs-dir", str(tmp_path), "--name", "toy", "--domain",
                    str(ros_domain), "--quiet", "--no-markers", "--timeout", "300"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    records = runner_records(toy_learner.TOY, movements=MOVEMENTS, eval_every=0)
    output, _ = child.communicate(timeout=330)
    assert child.returncode == 0, output[-3000:]
    run = load_run(tmp_path / "toy" / "bag")
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    assert bag_digest(run.movements) == runner_digest(records)
