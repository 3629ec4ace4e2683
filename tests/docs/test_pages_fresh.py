"""Every page a pinned experiment writes was made by today's learner, or says it was not
(issue 30): `ros_ws/reproduce.sh --check`, as the suite runs it."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.ros  # the graph's fingerprints read the nodes' declarations


def test_every_generated_page_is_fresh_or_carries_its_stale_banner(capsys):
    from sgim_nodes.experiments.cli import check
    from sgim_nodes.experiments.pinned import all_experiments

    assert check(all_experiments(), mark=False) == 0, capsys.readouterr().out
