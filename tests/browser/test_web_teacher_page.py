"""The web teacher's page in a real browser (headless Chromium), teaching a real run.

One short SGIM-D run with `--teacher web --wait-for-teacher forever` serves both tests: it
waits for the teacher before its first movement and every PERIOD movements, so the tests act
when they choose, on a machine however loaded. At its turns the page steps the run, then
demonstrates in each of its three ways: a click on an unreached teaching goal, a click on
another point and the confirmation of the action offered for it, 24 pasted numbers. The run
is checked from its bag.

SGIM_SCREENSHOT=path: also save the page's screenshot there (the README's figure is made so:
SGIM_SCREENSHOT=docs/figures/web_teacher.png ./test.sh tests/browser).
"""

from __future__ import annotations

import os
import re
import subprocess
import time

import numpy as np
import pytest

from sgim_nodes.core.config import LearnerConfig
from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
MOVEMENTS, PERIOD, SEED = 600, 150, 4  # teacher turns at 0, 150, 300 and 450
IMITATIONS = LearnerConfig().imitation_count


@pytest.fixture(scope="module")
def web_run(tmp_path_factory, ros_domain):
    """The run (waiting at its first teacher turn) and the page open on it."""
    from sgim_nodes.graph.processes import ProcessGroup, group_is_empty
    from teacher.web.headless import browser_page

    runs = tmp_path_factory.mktemp("web-runs")
    group = ProcessGroup(env=dict(os.environ), log_dir=runs / "logs")
    child = group.start("web-run", [
        RUN, "sgim-d", "--seed", str(SEED), "--movements", str(MOVEMENTS), "--eval-every",
        "100", "--period", str(PERIOD), "--teacher", "web", "--wait-for-teacher", "forever",
        "--web-port", "0", "--runs-dir", str(runs), "--name", "web", "--domain",
        str(ros_domain), "--quiet", "--timeout", "900"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    address = runs / "web" / "web_teacher.url"
    try:
        deadline = time.monotonic() + 120
        while not address.exists():
            assert child.poll() is None, child.stdout.read()[-3000:]
            assert time.monotonic() < deadline, "the web teacher never served its page"
            time.sleep(0.2)
        with browser_page() as page:
            page.goto(address.read_text().strip())
            yield child, page, runs / "web"
    finally:
        group.stop_all()
        leftovers = [c.pid for c in group.children if not group_is_empty(c.pid)]
        assert not leftovers, f"processes left behind: {leftovers}"


def message(page) -> str:
    return page.locator("#message").inner_text()


def wait_for_message(page, pattern: str, timeout: float = 30.0) -> str:
    from playwright.sync_api import TimeoutError as PageTimeout

    try:
        page.wait_for_function(
            "p => new RegExp(p).test(document.querySelector('#message').textContent)",
            arg=pattern, timeout=timeout * 1000)
    except PageTimeout:
        log = page.locator("#log").inner_text()
        pytest.fail(f"no message {pattern!r} in {timeout:g} s; the page says "
                    f"{message(page)!r}; its log:\n{log}")
    return message(page)


def wait_for_turn(page, movement: int, timeout: float = 180.0) -> None:
    """Until the page shows the teacher's turn at ``movement``."""
    page.wait_for_function(
        "m => document.querySelector('#pace-state').textContent.startsWith('your turn') "
        "&& Number(document.querySelector('#count').textContent) === m",
        arg=movement, timeout=timeout * 1000)


def test_bad_input_from_the_page_is_refused_with_a_message(web_run):
    _, page, _ = web_run
    wait_for_turn(page, 0)
    for text, expected in [
            ("1 2 3", "the pasted action has 3 numbers, 24 are needed"),
            (" ".join(["0.1"] * 23 + ["2"]), r"the pasted action\[23\] = 2 is outside \[-1, 1\]"),
            (" ".join(["nan"] + ["0"] * 23), r"the pasted action\[0\] is NaN"),
            ("", "the pasted action is empty"),
            (", ".join(["0.1"] * 23 + ["x"]), r"the pasted action\[23\] is 'x', not a number")]:
        page.fill("#action-text", text)
        page.click("#send-action")
        assert re.search(expected, wait_for_message(page, expected))
        assert page.locator("#message").get_attribute("class") == "error"
    # The refusals are in the page's log too, and nothing was sent.
    page.wait_for_function("document.querySelectorAll('#log li.error').length >= 5")
    assert page.locator("#demos").inner_text() == "0"
    # A command the server cannot read is refused with a message, not a crash.
    reply = page.evaluate("""async () => {
        const r = await fetch('/api/command', {method: 'POST', body: '{"command": "teach", '
            + '"index": 999}', headers: {'X-Teacher': '1'}});
        return await r.json(); }""")
    from sim_bridge.data_files import load_teaching_set

    last = len(load_teaching_set().outcomes) - 1
    assert reply == {"ok": False, "message": f"no teaching-set entry 999: entries are 0 to {last}"}
    forged = page.evaluate("""async () => (await fetch('/api/command', {method: 'POST',
        body: '{"command": "pace", "what": "pause"}'})).status""")
    assert forged == 403  # no X-Teacher header: what a cross-site form would send


def far_point(page) -> tuple[tuple[float, float], dict[str, float]]:
    """A point of the outcome space far from every teaching goal, and where it is drawn."""
    width = page.evaluate("document.querySelector('#overlay').width")
    outcomes = np.array(page.evaluate("window.teacherPage.view.teaching.outcomes"))
    grid = np.linspace(-0.8, 0.8, 17)
    points = np.array([(x, y) for x in grid for y in grid])
    far = np.linalg.norm(points[:, None, :] - outcomes[None], axis=2).min(axis=1)
    x, y = points[int(np.argmax(far))]
    assert far.max() * width / 2 > 20  # pixels: not a click on a teaching goal
    return (float(x), float(y)), {"x": (x + 1) / 2 * width, "y": (1 - y) / 2 * width}


def test_teach_a_run_from_the_page(web_run):
    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.reader import load_run
    from sim_bridge.data_files import load_teaching_set

    teaching = load_teaching_set()

    child, page, run_dir = web_run
    wait_for_turn(page, 0)
    assert page.locator("#total").inner_text() == str(MOVEMENTS)  # the budget
    # Step 3 movements (this ends the turn without a demonstration), then go on.
    page.fill("#step-count", "3")
    page.click("#step")
    wait_for_message(page, "stepping 3 movements")
    page.wait_for_function("document.querySelector('#pace-state').textContent === 'paused' "
                           "&& document.querySelector('#count').textContent === '3'",
                           timeout=60_000)
    time.sleep(1.0)
    assert page.locator("#count").inner_text() == "3"  # a step pauses again
    page.click("#resume")
    wait_for_message(page, "^resumed")
    # Landings appear as the run goes, coloured by process, until the next turn.
    page.wait_for_function("window.teacherStats.landings > 20", timeout=120_000)
    wait_for_turn(page, PERIOD)
    landed = page.evaluate("window.teacherStats.landings")
    assert 20 < landed <= PERIOD
    # Pause at the turn, so that the run stands still after the demonstration.
    page.click("#pause")
    wait_for_message(page, f"pausing at movement {PERIOD}")
    # Click an unreached (red) teaching goal on the picture.
    reached = page.evaluate("window.teacherPage.view.teaching.reached")
    unreached = [i for i, r in enumerate(reached) if not r]
    assert unreached, "every teaching goal reached after 150 movements: nothing to click"
    goal = unreached[len(unreached) // 2]
    at = page.evaluate(f"window.teacherPage.teachingPixel({goal})")
    page.locator("#overlay").click(position={"x": at["x"], "y": at["y"]})
    sent = wait_for_message(page, "sent demonstration 1")
    assert f"teaching-set entry {goal}" in sent
    # The demonstration ended the turn, the pause holds the run: its cast is drawn meanwhile.
    page.wait_for_function("document.querySelector('#pace-state').textContent === 'paused'",
                           timeout=60_000)
    paused_at = int(page.locator("#count").inner_text())
    assert paused_at == PERIOD
    page.wait_for_function("!document.querySelector('#cast').classList.contains('hidden') && "
                           "document.querySelector('#cast').naturalWidth > 0", timeout=300_000)
    assert f"demonstration 1: teaching-set entry {goal}" in page.locator(
        "#cast-caption").inner_text()
    time.sleep(1.0)
    assert int(page.locator("#count").inner_text()) == paused_at  # paused means paused
    page.click("#resume")

    # Next turn: click a point far from every teaching goal, be offered the library's most
    # reliable action for it with the outcome it gives, and confirm it.
    wait_for_turn(page, 2 * PERIOD)
    point, pixel = far_point(page)
    page.locator("#overlay").click(position=pixel)
    assert re.search(r"^offer \d+: for goal ", wait_for_message(page, "^offer "))
    offer = page.evaluate("window.teacherPage.view.offer")
    assert np.allclose(offer["goal"], point, atol=0.01)
    assert page.locator("#offer").is_visible()
    shown = page.locator("#offer-text").inner_text()
    expected = "outcome ({:+.3f}, {:+.3f})".format(*offer["outcome"])
    assert shown == offer["text"] and expected in shown
    page.click("#confirm")
    assert "sent demonstration 2 at movement 300" in wait_for_message(page, "sent demonstration 2")
    assert not page.locator("#offer").is_visible()

    # Last turn: paste 24 numbers; their outcome is measured (a cast not recorded) first.
    wait_for_turn(page, 3 * PERIOD)
    entry = (goal + 1) % len(teaching.actions)
    pasted = [round(float(v), 6) for v in teaching.actions[entry]]
    page.fill("#action-text", ", ".join(repr(v) for v in pasted))
    page.click("#send-action")
    sent = wait_for_message(page, "sent demonstration 3", timeout=120)
    assert "sent demonstration 3 at movement 450: the action of the pasted action, executed" in sent
    output, _ = child.communicate(timeout=300)
    assert child.returncode == 0, output[-3000:]
    assert "teach at http://127.0.0.1:" in output
    # The page knows the run is over and says so when asked for another demonstration.
    page.wait_for_function("document.querySelector('#run-state').textContent.startsWith('finished')",
                           timeout=30_000)
    page.locator("#overlay").click(position={"x": at["x"], "y": at["y"]})
    assert "the run is over (finished)" in wait_for_message(page, "the run is over")
    stats = page.evaluate("window.teacherStats")
    assert stats["updates"] > 20 and stats["landings"] > landed
    view = page.evaluate("window.teacherPage.view")
    legend = page.locator("#legend").inner_text()
    assert all(name in legend for name in ("own goal", "exploration", "imitation",
                                           "demonstration", "interest: low", "unreached"))
    if os.environ.get("SGIM_SCREENSHOT"):
        page.evaluate("window.scrollTo(0, 0)")
        page.screenshot(path=os.environ["SGIM_SCREENSHOT"], full_page=True)

    # The bag: the learner received exactly these demonstrations and imitated each at once.
    run = load_run(run_dir / "bag")
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    clicked, offered, measured = run.demonstrations
    assert [d.source for d in run.demonstrations] == ["web"] * 3
    assert [d.movement_index for d in run.demonstrations] == [PERIOD, 2 * PERIOD, 3 * PERIOD]
    assert clicked.teaching_set_index == goal
    assert np.array_equal(clicked.action, teaching.actions[goal])
    assert np.array_equal(clicked.outcome, teaching.outcomes[goal])
    assert offered.teaching_set_index == offer["teaching_set_index"]
    assert np.allclose(offered.outcome, offer["outcome"], rtol=0, atol=1e-9)
    if offer["teaching_set_index"] >= 0:
        assert np.array_equal(offered.action, teaching.actions[offer["teaching_set_index"]])
    assert measured.teaching_set_index == -1 and np.allclose(measured.action, pasted)
    # What the simulator measured: near the entry's own outcome (motor noise aside).
    assert np.linalg.norm(measured.outcome - teaching.outcomes[entry]) < 0.15
    for demo in run.demonstrations:
        at = demo.movement_index
        follow = run.movements[at: at + IMITATIONS]
        assert all(m.process == Movement.PROCESS_IMITATION for m in follow)
        assert all(np.allclose(m.goal, demo.outcome) for m in follow)
        assert all(np.linalg.norm(m.action - demo.action) < LearnerConfig().imitation_epsilon
                   for m in follow)
    imitations = [m for m in run.movements if m.process == Movement.PROCESS_IMITATION]
    assert len(imitations) == 3 * IMITATIONS
    # The page drew the run's own error curve, region tree and goals.
    page_errors = {int(m): d for m, d in view["evaluations"]}
    bag_errors = {e.movement_index: e.mean_distance for e in run.evaluations}
    assert len(page_errors) >= len(bag_errors) - 1 >= 5
    assert all(bag_errors.get(m) == d for m, d in page_errors.items())
    drawn = sorted(tuple(round(v, 9) for v in rect[:4]) for rect in view["regions"]["rects"])
    assert any(drawn == sorted(tuple(round(float(v), 9) for v in (*r.lower, *r.upper))
                               for r in snapshot.leaves) for snapshot in run.region_map)
    assert view["goal"] is not None and all(-1 <= v <= 1 for v in view["goal"])
    # The page's picture was the run's: every landing of the bag was drawn.
    landed_in_bag = sum(m.status == Movement.STATUS_OK for m in run.movements)
    assert stats["landings"] == landed_in_bag
