"""The runner reproduces the reference runs' digests (tests/golden_runs.py) on this machine's
own BLAS kernel and SIMD level: a change of shared core code (a new learner, a new random
stream, a new config field) must leave the existing learners' movements bit for bit."""

import pytest

from tests.golden_runs import DIGESTS, runner_digest, runner_records


@pytest.mark.slow
@pytest.mark.parametrize("learner", sorted(DIGESTS))
def test_the_runner_gives_the_reference_digest(learner):
    assert runner_digest(runner_records(learner)) == DIGESTS[learner]
