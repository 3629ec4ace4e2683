"""A person teaches SGIM-ACTS from the web page, as one of its teachers.

Two short sgim-acts runs: one whose only teacher is the web page (`--teacher web --param
teachers=web`), one with the page beside the three experts and the next choice (region first,
pairs valued by their gain; docs/active_strategies.md). The learner asks the page, and this
test answers every request to it through the page's own API, as the page's buttons do, in
turn with a teaching entry and with "none there". The page's log says each episode's strategy
and each request; the bag holds the requests, the answers (source "expert:web", each naming
its request) and the competences of the episodes, "none there" ones at -1 without a movement.
"""

from __future__ import annotations

import json
import subprocess
import time
import urllib.request
import uuid

import numpy as np
import pytest

from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS = 120


def api(url: str, path: str, body: dict | None = None) -> dict:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(
        url.rstrip("/") + path, data=data, method="POST" if data else "GET",
        headers={"Content-Type": "application/json", "X-Teacher": "1"})  # as the page sends
    with urllib.request.urlopen(request, timeout=30) as reply:
        return json.loads(reply.read())


NEXT_CHOICE = ["--param", "strategy_choice_order=region-first", "--param",
               "strategy_value=gain"]


@pytest.mark.parametrize("settings", [["--param", "teachers=web"], NEXT_CHOICE],
                         ids=["the-only-teacher", "beside-the-experts-next-choice"])
def test_a_person_answers_sgim_acts_from_the_page(ros_processes, ros_domain, tmp_path,
                                                  settings):
    from sgim_msgs.msg import RunStatus
    from sgim_nodes.bag.reader import load_run

    child = ros_processes.start("acts-web", [
        RUN, "sgim-acts", "--seed", "2", "--movements", str(MOVEMENTS), "--eval-every", "60",
        "--teacher", "web", *settings, "--web-port", "0", "--web-linger", "0",
        "--runs-dir", str(tmp_path), "--name", "web", "--domain", str(ros_domain), "--quiet",
        "--timeout", "600"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    address = tmp_path / "web" / "web_teacher.url"
    deadline = time.monotonic() + 180
    while not address.exists():
        assert child.poll() is None, child.stdout.read()[-3000:]
        assert time.monotonic() < deadline, "the web teacher never served its page"
        time.sleep(0.1)
    url = address.read_text().strip()
    log_cursor, answered, lines = 0, [], []
    while child.poll() is None and time.monotonic() < deadline + 400:
        try:
            state = api(url, f"/api/state?log={log_cursor}")
        except OSError:  # the page ends with the run
            break
        assert state["expert"] == "web"
        for number, _level, text in state["log"]:
            log_cursor = max(log_cursor, number)
            lines.append(text)
            if text.startswith("request "):  # answer it, in turn one way or the other
                if len(answered) % 2 == 0:
                    reply = api(url, "/api/command", {"command": "teach",
                                                      "index": len(answered) % 29,
                                                      "key": uuid.uuid4().hex})
                else:
                    reply = api(url, "/api/command", {"command": "none"})
                assert reply["ok"], reply
                answered.append(int(text.split()[1].rstrip(":")))
        time.sleep(0.2)
    output, _ = child.communicate(timeout=120)
    assert child.returncode == 0, output[-3000:]
    assert any(line.startswith("episode at movement") and ":web" in line for line in lines)

    run = load_run(tmp_path / "web" / "bag")
    assert run.run_status[-1].state == RunStatus.STATE_FINISHED
    asks = [a for a in run.help_requests if a.teacher == "web"]
    assert len(asks) >= 2
    if settings == NEXT_CHOICE:  # the experts were asked too
        assert {a.teacher for a in run.help_requests} > {"web"}
    else:
        assert {a.teacher for a in run.help_requests} == {"web"}
    assert [a.index for a in asks] == answered
    replies = {d.help_request: d for d in run.demonstrations if d.source == "expert:web"}
    assert sorted(replies) == answered
    for k, index in enumerate(answered):
        ask, reply = asks[k], replies[index]
        assert reply.movement_index == ask.movement_index
        shown = len(reply.outcome) > 0
        assert shown == (k % 2 == 0)
        if shown:  # an entry of the teaching set, its action only for mimicry
            assert reply.teaching_set_index == k % 29
            assert (len(reply.action) > 0) == (ask.content == "means-and-goal")
    social = [c for c in run.competences if c.strategy.endswith(":web")]
    assert len(social) >= len(answered) - 1  # the budget may cut the last episode
    nothing = [c for c in social if c.movements_used == 0]
    assert nothing and all(c.competence == -1.0 and not len(c.reached) for c in nothing)
    assert all(np.all(np.abs(c.goal) <= 1.0) for c in social)

