"""The web teacher's page in a real browser (headless Chromium), teaching a real run, as a
person on another machine would: the page served on this machine's non-loopback address
with an access token.

One short SGIM-D run with `--teacher web --wait-for-teacher forever` serves every test, in
order: it waits for the teacher before its first movement and every PERIOD movements, so each
test acts at its own turn, on a machine however loaded. The page opened without its token (or
with a wrong one) says what to open. At the turns the page steps the run (also while it moves:
the step counts from where it stops), then demonstrates in every way a person can: a double
click on an unreached teaching goal (one demonstration), a pick among goals drawn too close to
click apart, a reached goal taught again on purpose, the confirmation of an action offered for
another point, 24 pasted numbers. After the run, the map's and the error chart's axes are
checked against what they label, and the page stays (`--web-linger`) until the person closes
it. The run is then checked from its bag.

The address: the machine's own IPv4 address (`hostname -I`); a machine with none but
loopback serves on every interface and the browser opens it by a name it resolves to
127.0.0.1 (to the browser a remote origin all the same: not a secure context).

SGIM_SCREENSHOT=path: also save the page's screenshot there, taken after the run (the README's
figure is made so: SGIM_SCREENSHOT=docs/figures/web_teacher.png ./test.sh tests/browser).
"""

from __future__ import annotations

import ipaddress
import json
import os
import re
import subprocess
import time
from urllib.parse import urlsplit, urlunsplit

import numpy as np
import pytest

from sgim_nodes.core.config import LearnerConfig
from tests.conftest import REPO

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RUN = str(REPO / "ros_ws" / "run_experiment.sh")
PERIOD, SEED = 40, 4
MOVEMENTS = 6 * PERIOD  # teacher turns at 0, 40, 80, 120, 160 and 200: one test each
IMITATIONS = LearnerConfig().imitation_count
TOKEN = "browser-test-token-0123456789"
PICK_PX = 10  # teacher.js: a click this near a teaching goal picks it
LINGER = 120  # seconds the page may stay after the run (the test closes it before)


def page_host() -> tuple[str, str, list[str]]:
    """(--web-host, the host the browser opens, more Chromium flags)."""
    try:
        found = subprocess.run(["hostname", "-I"], capture_output=True, text=True,
                               timeout=10).stdout.split()
    except (OSError, subprocess.SubprocessError):
        found = []
    for address in found:
        ip = ipaddress.ip_address(address)
        if ip.version == 4 and not ip.is_loopback and not ip.is_link_local:
            return address, address, []
    return "0.0.0.0", "teacher.test", ["--host-resolver-rules=MAP teacher.test 127.0.0.1"]


@pytest.fixture(scope="module")
def web_run(tmp_path_factory, ros_domain):
    """The run (waiting at its first teacher turn) and the page open on it."""
    from sgim_nodes.graph.processes import ProcessGroup, group_is_empty
    from teacher.web.headless import browser_page

    host, browse, flags = page_host()
    runs = tmp_path_factory.mktemp("web-runs")
    group = ProcessGroup(env=dict(os.environ), log_dir=runs / "logs")
    child = group.start("web-run", [
        RUN, "sgim-d", "--seed", str(SEED), "--movements", str(MOVEMENTS), "--eval-every",
        str(3 * PERIOD), "--demonstration-period", str(PERIOD), "--teacher", "web",
        "--wait-for-teacher", "forever", "--web-host", host, "--web-token", TOKEN, "--web-port",
        "0", "--web-linger", str(LINGER), "--runs-dir", str(runs), "--name", "web", "--domain",
        str(ros_domain), "--quiet", "--timeout", "900"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    address = runs / "web" / "web_teacher.url"
    try:
        with browser_page(flags=flags) as page:  # Chromium starts while the graph does
            deadline = time.monotonic() + 120
            while not address.exists():
                assert child.poll() is None, child.stdout.read()[-3000:]
                assert time.monotonic() < deadline, "the web teacher never served its page"
                time.sleep(0.1)
            url = urlsplit(address.read_text().strip())
            page.goto(urlunsplit(url._replace(netloc=f"{browse}:{url.port}")))
            yield child, page, runs / "web", host
    finally:
        group.stop_all()
        leftovers = [c.pid for c in group.children if not group_is_empty(c.pid)]
        assert not leftovers, f"processes left behind: {leftovers}"


def message(page) -> str:
    return page.locator("#message").inner_text()


def refusals(page) -> int:
    return sum(line.startswith("refused") for line in page.locator("#log li").all_inner_texts())


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


def wait_for_pause(page, movement: int) -> None:
    """Until the page shows the run paused at ``movement``."""
    page.wait_for_function("m => document.querySelector('#pace-state').textContent === "
                           "'paused' && Number(document.querySelector('#count').textContent) "
                           "=== m", arg=movement, timeout=60_000)


def goal_pixels(page) -> np.ndarray:
    return np.array([[p["x"], p["y"]] for p in page.evaluate(
        "[...window.teacherPage.view.teaching.outcomes.keys()]"
        ".map(i => window.teacherPage.teachingPixel(i))")])


def lone_goals(page, reached: bool) -> list[int]:
    """Teaching goals with no other one near enough to share a click, reached or not."""
    pixels = goal_pixels(page)
    states = page.evaluate("window.teacherPage.view.teaching.reached")
    gaps = np.linalg.norm(pixels[:, None] - pixels[None], axis=2)
    np.fill_diagonal(gaps, np.inf)
    return [i for i, r in enumerate(states) if r == reached and gaps[i].min() > 2 * PICK_PX]


def fetch(page, path: str, body: str | None = None, headers: str = "{}") -> dict:
    """What the page's own origin gets for ``path``: status and JSON (or text) answer."""
    return page.evaluate(f"""async () => {{
        const r = await fetch({path!r}, {{method: {'"POST"' if body else '"GET"'},
            headers: {headers}{', body: ' + repr(body) if body else ''}}});
        const text = await r.text();
        let json = null; try {{ json = JSON.parse(text); }} catch (e) {{}}
        return {{status: r.status, type: r.headers.get('Content-Type'), json}}; }}""")


def test_the_page_works_with_a_token_on_another_address(web_run):
    """index.html fetched its stylesheet and script without the token: 401, a page unstyled
    and dead. Now they come without it, and the run's data still needs it."""
    _, page, _, _ = web_run
    wait_for_turn(page, 0)
    assert urlsplit(page.url).hostname not in ("127.0.0.1", "localhost", "::1")
    assert page.evaluate("window.isSecureContext") is False  # a remote origin to the browser
    header = page.evaluate("getComputedStyle(document.querySelector('header')).backgroundColor")
    assert header == "rgb(32, 48, 63)"  # teacher.css applied
    assert page.evaluate("window.teacherStats.updates") > 0  # teacher.js polls
    assert page.locator("#total").inner_text() == str(MOVEMENTS)
    for path in ("/static/teacher.css", "/static/teacher.js", "/"):
        assert fetch(page, path)["status"] == 200, path
    for path in ("/api/state", "/api/legend", "/lake.png"):
        assert fetch(page, path)["status"] == 401, path
    assert fetch(page, "/api/state", headers=f"{{'X-Teacher-Token': {TOKEN!r}}}")["status"] == 200
    # The title names the run's learner (it said SGIM-D whatever the run).
    page.wait_for_function("document.title === 'SGIM-D web teacher'")
    assert page.locator("#title").inner_text() == "SGIM-D web teacher"


def test_the_page_without_its_token_says_which_address_to_open(web_run):
    """It said only 'the web teacher does not answer (401)'; the server's words say more."""
    _, page, _, _ = web_run
    address = urlsplit(page.url)
    other = page.context.new_page()
    try:
        for query, what in (("", "no access token"), ("token=not-the-token", "a wrong access "
                                                       "token")):
            other.goto(urlunsplit(address._replace(query=query)))
            other.wait_for_selector("#problem:not(.hidden)")
            assert other.locator("#problem").inner_text().startswith(
                f"{what}: open this page at the address the run printed after 'teach at', "
                "with its ?token=")
            assert other.locator("#run-state").inner_text() == "no access: see the message below"
    finally:
        other.close()


def test_bad_input_from_the_page_is_refused_with_a_message(web_run):
    _, page, _, _ = web_run
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
    auth = f"{{'X-Teacher-Token': {TOKEN!r}, 'X-Teacher': '1'}}"
    # A command the server cannot read is refused with a message, not a crash.
    from sim_bridge.data_files import load_teaching_set

    last = len(load_teaching_set().outcomes) - 1
    reply = fetch(page, "/api/command", '{"command": "teach", "index": 999, "key": "k-000000001"}',
                  auth)["json"]
    assert reply == {"ok": False, "message": f"no teaching-set entry 999: entries are 0 to {last}"}
    for body, words in (('{"command": "confirm", "offer": [1], "key": "k-000000002"}',
                         "no offer [1]"),
                        ('{"command": "teach", "index": 1}', "needs a 'key'")):
        reply = fetch(page, "/api/command", body, auth)
        assert reply["status"] == 200 and words in reply["json"]["message"]
    forged = fetch(page, "/api/command", '{"command": "pace", "what": "pause"}',
                   f"{{'X-Teacher-Token': {TOKEN!r}}}")
    assert forged["status"] == 403  # no X-Teacher header: what a cross-site form would send
    # The button stays disabled until the answer comes: a second click sends nothing.
    page.evaluate("""() => { const send = window.realFetch = window.fetch;
        window.commandsSent = 0;
        window.fetch = (url, options) => url !== '/api/command' ? send(url, options)
            : (window.commandsSent += 1, new Promise(r => setTimeout(r, 700))
                .then(() => send(url, options))); }""")
    page.fill("#action-text", "1 2 3")
    page.click("#send-action")
    assert page.locator("#send-action").is_disabled() and page.locator("#pause").is_disabled()
    page.locator("#send-action").click(force=True)  # what a second click does: nothing
    wait_for_message(page, "the pasted action has 3 numbers")
    page.wait_for_function("!document.querySelector('#send-action').disabled")
    assert page.evaluate("window.commandsSent") == 1
    page.evaluate("window.fetch = window.realFetch")


def test_step_then_a_double_click_demonstrates_once(web_run):
    _, page, _, _ = web_run
    wait_for_turn(page, 0)
    # Step 3 movements (this ends the turn without a demonstration), then go on.
    page.fill("#step-count", "3")
    page.click("#step")
    assert wait_for_message(page, "stepping 3 movements") == (
        "stepping 3 movements from movement 0: it pauses again at movement 3")
    wait_for_pause(page, 3)
    time.sleep(0.5)
    assert page.locator("#count").inner_text() == "3"  # a step pauses again
    # A step asked while a job runs counts from where the run stops, and pauses there plus
    # its movements (it was counted from the job's start, and went on to the job's end).
    page.fill("#step-count", "30")
    page.click("#step")
    wait_for_message(page, "stepping 30 movements from movement 3")
    page.fill("#step-count", "2")
    page.click("#step")
    said = wait_for_message(page, "stepping 2 movements from movement")
    start = int(re.search(r"from movement (\d+): it pauses again at movement (\d+)",
                          said)[1])
    assert 3 <= start <= 33 and said.endswith(f"movement {start + 2}")
    wait_for_pause(page, start + 2)
    time.sleep(0.5)
    assert int(page.locator("#count").inner_text()) == start + 2
    page.click("#resume")
    wait_for_message(page, "^resumed")
    # Landings appear as the run goes, coloured by process, until the next turn.
    wait_for_turn(page, PERIOD)
    assert 10 < page.evaluate("window.teacherStats.landings") <= PERIOD
    # Pause at the turn, so that the run stands still after the demonstration.
    page.click("#pause")
    wait_for_message(page, f"^paused at movement {PERIOD}$")
    # A double click on an unreached (red) teaching goal: one demonstration.
    goals = lone_goals(page, reached=False)
    assert goals, "no unreached teaching goal to click"
    goal = goals[len(goals) // 2]
    at = page.evaluate(f"window.teacherPage.teachingPixel({goal})")
    refused_before = refusals(page)
    page.locator("#overlay").dblclick(position={"x": at["x"], "y": at["y"]})
    sent = wait_for_message(page, "sent demonstration 1")
    assert f"teaching-set entry {goal}" in sent
    page.wait_for_function("document.querySelector('#pace-state').textContent === 'paused'",
                           timeout=60_000)
    # The double click's second click was ignored by the page, not refused by the node.
    assert refusals(page) == refused_before
    # Another one now, with a key of its own, would cut the imitation short: refused.
    auth = f"{{'X-Teacher-Token': {TOKEN!r}, 'X-Teacher': '1'}}"
    reply = fetch(page, "/api/command",
                  f'{{"command": "teach", "index": {goal}, "key": "another-key-1"}}', auth)
    assert "demonstration 1 (sent at movement 40) is not imitated to its end yet" in reply[
        "json"]["message"]
    time.sleep(0.5)
    assert int(page.locator("#count").inner_text()) == PERIOD  # paused means paused
    assert page.locator("#demos").inner_text() == "1"
    sent_lines = page.locator("#log li.sent").all_inner_texts()
    assert len(sent_lines) == 1, sent_lines
    page.click("#resume")
    wait_for_message(page, "^resumed")


def test_goals_drawn_too_close_to_click_apart_are_picked_from_a_list(web_run):
    _, page, _, _ = web_run
    wait_for_turn(page, 2 * PERIOD)
    pixels = goal_pixels(page)
    gaps = np.linalg.norm(pixels[:, None] - pixels[None], axis=2)
    np.fill_diagonal(gaps, np.inf)
    a, b = np.unravel_index(np.argmin(gaps), gaps.shape)
    assert gaps[a, b] < PICK_PX, "the teaching set has no two goals drawn that close"
    middle = (pixels[a] + pixels[b]) / 2
    page.locator("#overlay").click(position={"x": float(middle[0]), "y": float(middle[1])})
    page.wait_for_selector("#pick:not(.hidden)")
    listed = [int(i) for i in page.locator("#pick-list button").evaluate_all(
        "bs => bs.map(b => b.dataset.index)")]
    assert sorted(listed) == sorted([int(a), int(b)])
    page.click(f"#pick-list button[data-index='{listed[1]}']")
    sent = wait_for_message(page, "sent demonstration 2")
    assert f"teaching-set entry {listed[1]}," in sent
    assert not page.locator("#pick").is_visible()


def test_a_reached_goal_can_be_demonstrated_again_on_purpose(web_run):
    _, page, _, _ = web_run
    wait_for_turn(page, 3 * PERIOD)
    reached = lone_goals(page, reached=True)
    assert reached, "no reached teaching goal away from the others"
    goal = reached[0]
    at = page.evaluate(f"window.teacherPage.teachingPixel({goal})")
    page.locator("#overlay").click(position={"x": at["x"], "y": at["y"]})
    page.wait_for_selector("#pick:not(.hidden)")
    button = page.locator("#pick-list button")
    assert button.count() == 1 and button.inner_text() == f"Demonstrate entry {goal} again"
    assert page.locator("#message").inner_text().startswith("sent demonstration 2")  # no offer
    button.click()
    sent = wait_for_message(page, "sent demonstration 3")
    assert f"teaching-set entry {goal}," in sent and "already reached it" in sent


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


def legend_and_drawn(page) -> tuple[dict[str, list[int] | None], set[str]]:
    legend = {e["mark"]: e["rgb"] for e in page.evaluate("window.teacherPage.legend()")}
    return legend, set(page.evaluate("window.teacherPage.drawn()"))


def test_an_offer_says_its_cost_is_lower_is_better_and_the_legend_shows_it(web_run):
    _, page, run_dir, _ = web_run
    wait_for_turn(page, 4 * PERIOD)
    point, pixel = far_point(page)
    page.locator("#overlay").click(position=pixel)
    assert re.search(r"^offer \d+: for goal ", wait_for_message(page, "^offer "))
    offer = page.evaluate("window.teacherPage.view.offer")
    assert np.allclose(offer["goal"], point, atol=0.01)
    shown = page.locator("#offer-text").inner_text()
    expected = "outcome ({:+.3f}, {:+.3f})".format(*offer["outcome"])
    assert shown == offer["text"] and expected in shown
    assert "lower is better" in shown and "reliability" not in shown
    assert "lower is better" in page.locator("#offer .hint").inner_text()
    legend, drawn = legend_and_drawn(page)
    assert "offer" in drawn and set(legend) == drawn
    page.click("#confirm")
    assert "sent demonstration 4 at movement 160" in wait_for_message(
        page, "sent demonstration 4")
    assert not page.locator("#offer").is_visible()
    page.wait_for_function("!window.teacherPage.drawn().includes('offer')")
    assert "offer" not in legend_and_drawn(page)[0]
    (run_dir / "offer.json").write_text(json.dumps(offer))


def test_a_pasted_action_is_measured_then_demonstrated(web_run):
    from sim_bridge.data_files import load_teaching_set

    _, page, _, _ = web_run
    wait_for_turn(page, 5 * PERIOD)
    teaching = load_teaching_set()
    pasted = [round(float(v), 6) for v in teaching.actions[0]]
    page.fill("#action-text", ", ".join(repr(v) for v in pasted))
    page.click("#send-action")
    sent = wait_for_message(page, "sent demonstration 5", timeout=120)
    assert "sent demonstration 5 at movement 200: the action of the pasted action, executed" in sent


def _lab(rgb) -> np.ndarray:
    """CIE L*a*b* (D65) of an sRGB colour, to compare colours as eyes do."""
    c = np.asarray(rgb, dtype=float) / 255
    c = np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722],
                    [0.0193, 0.1192, 0.9505]]) @ c / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def delta_e(a, b) -> float:
    return float(np.linalg.norm(_lab(a) - _lab(b)))


def test_the_legend_shows_every_mark_drawn_and_only_those_in_distinct_colours(web_run):
    _, page, _, _ = web_run
    page.wait_for_function("document.querySelector('#run-state').textContent"
                           ".startsWith('finished')", timeout=180_000)
    legend, drawn = legend_and_drawn(page)
    assert set(legend) == drawn
    assert {"landing-0", "landing-2", "water", "land", "shore", "interest", "unreached",
            "reached", "demonstration", "goal"} <= drawn
    names = page.locator("#legend").inner_text()
    assert "own goal" in names and "imitation" in names and "teaching goal, reached" in names
    assert "landing-3" not in legend  # the demonstration process: its casts never land
    coloured = {m: rgb for m, rgb in legend.items() if rgb is not None}
    close = [(a, b) for a in coloured for b in coloured
             if a < b and delta_e(coloured[a], coloured[b]) < 20]
    assert not close, close


def test_the_map_and_the_error_chart_have_axes_in_metres(web_run):
    """The map had no axes, scale or units, the error chart a bare 0 and maximum."""
    from sim_bridge.scaling import OUTCOME_BOX

    _, page, _, _ = web_run
    page.wait_for_function("document.querySelector('#run-state').textContent"
                           ".startsWith('finished')", timeout=180_000)
    lo, hi = float(OUTCOME_BOX[0]), float(OUTCOME_BOX[1])
    axes = page.evaluate("""() => {
        const box = document.querySelector('#overlay').getBoundingClientRect();
        const ticks = (id) => [...document.querySelectorAll(`#${id} text.tick-label`)].map(e => {
            const r = e.getBoundingClientRect();
            return {v: Number(e.dataset.value), x: r.x + r.width / 2, y: r.y + r.height / 2}; });
        const titles = (id) => [...document.querySelectorAll(`#${id} text.title`)]
            .map(e => e.textContent);
        return {box: {x: box.x, y: box.y, w: box.width, h: box.height},
                x: ticks('x-axis'), y: ticks('y-axis'), xt: titles('x-axis'),
                yt: titles('y-axis'), et: titles('errors')}; }""")
    box = axes["box"]
    assert axes["xt"] == ["x (m), forward from the robot"]
    assert axes["yt"] == ["y (m), to the robot's left"]
    assert [t["v"] for t in axes["x"]] == [t["v"] for t in axes["y"]] == list(range(-8, 9, 2))
    for tick in axes["x"]:  # each label under the place of its value on the map
        u = 2 * (tick["v"] - lo) / (hi - lo) - 1
        assert abs(tick["x"] - (box["x"] + (u + 1) / 2 * box["w"])) < 2, tick
    for tick in axes["y"]:
        u = 2 * (tick["v"] - lo) / (hi - lo) - 1
        assert abs(tick["y"] - (box["y"] + (1 - u) / 2 * box["h"])) < 3, tick
    caption = page.locator("#map-caption").inner_text()
    assert "metres" in caption and "divided by 8.5" in caption
    assert "came down on land" in page.locator("#failed-hint").inner_text()
    # The error chart: one title per axis, and its last point where its y axis says.
    assert axes["et"] == ["movements", "error (m)"]
    chart = page.evaluate("""() => {
        const q = (s) => [...document.querySelectorAll(`#errors ${s}`)];
        return {y: q('text.tick-label.y').map(e => [Number(e.dataset.value),
                                                     Number(e.getAttribute('y')) - 4]),
                x: q('text.tick-label.x').map(e => Number(e.dataset.value)),
                points: q('circle.point').map(e => [Number(e.dataset.movement),
                    Number(e.dataset.value), Number(e.getAttribute('cy'))]),
                latest: q('text.latest').map(e => e.textContent)}; }""")
    errors = page.evaluate("window.teacherPage.view.evaluations")
    assert [p[0] for p in chart["points"]] == [e[0] for e in errors]
    metres = (hi - lo) / 2
    assert np.allclose([p[1] for p in chart["points"]], [e[1] * metres for e in errors])
    (v0, y0), (v1, y1) = chart["y"][0], chart["y"][-1]
    assert all(v0 <= p[1] <= v1 for p in chart["points"])  # the axis spans every point
    movement, value, cy = chart["points"][-1]
    assert abs(cy - (y0 + (value - v0) * (y1 - y0) / (v1 - v0))) < 0.5
    assert chart["x"][0] == 0 and chart["x"][-1] <= MOVEMENTS and len(chart["x"]) >= 3
    assert chart["latest"] == [f"{value:.2f} m at movement {movement}"]


def test_land_and_water_stay_visible_under_the_interest_shading(web_run):
    _, page, _, _ = web_run
    page.wait_for_function("document.querySelector('#run-state').textContent"
                           ".startsWith('finished')", timeout=180_000)
    # For each region of the tree: the mean colour of its water and of its land on the
    # canvas (shore and region borders left out).
    pairs = page.evaluate("""() => {
        const c = document.querySelector('#base'), W = c.width, H = c.height;
        const data = c.getContext('2d').getImageData(0, 0, W, H).data;
        const p = window.teacherPage, rects = p.view.regions.rects, out = [];
        const px = x => (x + 1) / 2 * W, py = y => (1 - y) / 2 * H;
        for (const [x0, y0, x1, y1] of rects) {
            const sums = {water: [0, 0, 0, 0], land: [0, 0, 0, 0]};
            for (let y = Math.ceil(py(y1)) + 3; y < py(y0) - 3; y += 2) {
                for (let x = Math.ceil(px(x0)) + 3; x < px(x1) - 3; x += 2) {
                    const s = p.surfaceAt(x, y);
                    if ([[-4, 0], [4, 0], [0, -4], [0, 4]].some(([dx, dy]) =>
                        p.surfaceAt(x + dx, y + dy) !== s)) continue;
                    const i = 4 * (y * W + x);
                    for (let k = 0; k < 3; k++) sums[s][k] += data[i + k];
                    sums[s][3] += 1;
                }
            }
            if (sums.water[3] > 20 && sums.land[3] > 20) out.push(
                [0, 1, 2].map(k => sums.water[k] / sums.water[3])
                .concat([0, 1, 2].map(k => sums.land[k] / sums.land[3])));
        }
        return out; }""")
    assert len(pairs) >= 2, "no region holds both land and water"
    worst = min(delta_e(p[:3], p[3:]) for p in pairs)
    assert worst >= 20, worst


def test_the_page_stays_after_the_run_until_closed_and_the_run_is_whole(web_run):
    from sgim_msgs.msg import Movement
    from sgim_nodes.bag.reader import load_run
    from sim_bridge.data_files import load_teaching_set

    child, page, run_dir, host = web_run
    page.wait_for_function("document.querySelector('#run-state').textContent"
                           ".startsWith('finished')", timeout=180_000)
    # The page says the run is over and stays: the launcher waits for the person.
    page.wait_for_selector("#over:not(.hidden)")
    assert page.locator("#over-title").inner_text() == (
        f"The run is over (finished at movement {MOVEMENTS}).")
    page.wait_for_function("/keeps showing it for \\d+ s more/.test("
                           "document.querySelector('#over-text').textContent)")
    assert page.locator("#close").is_visible()
    assert page.locator("#pause").is_disabled() and page.locator("#send-action").is_disabled()
    launcher_log = run_dir / "logs" / "launcher.log"
    deadline = time.monotonic() + 90  # the recorder's end first
    while f"its page stays for at most {LINGER} s" not in launcher_log.read_text():
        assert child.poll() is None and time.monotonic() < deadline, launcher_log.read_text()
        time.sleep(0.2)
    time.sleep(0.5)
    assert child.poll() is None  # the graph is still up for the page
    updates = page.evaluate("window.teacherStats.updates")
    page.wait_for_function(f"window.teacherStats.updates > {updates}")  # still answering
    page.locator("#overlay").click(position=far_point(page)[1])
    assert "the run is over (finished)" in wait_for_message(page, "the run is over")
    # The latest demonstration's cast is drawn meanwhile, for the page.
    page.wait_for_function("!document.querySelector('#cast').classList.contains('hidden') && "
                           "document.querySelector('#cast').naturalWidth > 0", timeout=300_000)
    assert "demonstration" in page.locator("#cast-caption").inner_text()
    stats = page.evaluate("window.teacherStats")
    view = page.evaluate("window.teacherPage.view")
    if os.environ.get("SGIM_SCREENSHOT"):
        page.evaluate("window.scrollTo(0, 0)")
        page.screenshot(path=os.environ["SGIM_SCREENSHOT"], full_page=True)
    # Closed by the person: the web teacher stops, the run ends, the page keeps its picture.
    page.click("#close")
    output, _ = child.communicate(timeout=120)
    assert child.returncode == 0, output[-3000:]
    assert f"teach at http://{host}:" in output
    page.wait_for_function("document.querySelector('#over-text').textContent"
                           ".startsWith('The web teacher has stopped')", timeout=30_000)
    assert page.evaluate("window.teacherStats.landings") == stats["landings"]

    # The bag: the learner received exactly these demonstrations and imitated each at once.
    teaching = load_teaching_set()
    run = load_run(run_dir / "bag")
    assert [m.index for m in run.movements] == list(range(1, MOVEMENTS + 1))
    assert [d.source for d in run.demonstrations] == ["web"] * 5
    assert [d.movement_index for d in run.demonstrations] == [PERIOD * k for k in range(1, 6)]
    offer = json.loads((run_dir / "offer.json").read_text())
    clicked, picked, again, offered, measured = run.demonstrations
    for demo in (clicked, picked, again):
        i = demo.teaching_set_index
        assert i >= 0 and np.array_equal(demo.action, teaching.actions[i])
        assert np.array_equal(demo.outcome, teaching.outcomes[i])
    assert offered.teaching_set_index == offer["teaching_set_index"]
    assert np.allclose(offered.outcome, offer["outcome"], rtol=0, atol=1e-9)
    assert measured.teaching_set_index == -1
    assert np.allclose(measured.action, [round(float(v), 6) for v in teaching.actions[0]])
    # What the simulator measured: near the entry's own outcome (motor noise aside).
    assert np.linalg.norm(measured.outcome - teaching.outcomes[0]) < 0.15
    for demo in run.demonstrations:
        at = demo.movement_index
        follow = run.movements[at: at + IMITATIONS]
        assert all(m.process == Movement.PROCESS_IMITATION for m in follow)
        assert all(np.allclose(m.goal, demo.outcome) for m in follow)
        assert all(np.linalg.norm(m.action - demo.action) < LearnerConfig().imitation_epsilon
                   for m in follow)
    imitations = [m for m in run.movements if m.process == Movement.PROCESS_IMITATION]
    assert len(imitations) == 5 * IMITATIONS  # none cut short
    # The page drew the run's own error curve, region tree and goals.
    page_errors = {int(m): d for m, d in view["evaluations"]}
    bag_errors = {e.movement_index: e.mean_distance for e in run.evaluations}
    assert len(page_errors) >= len(bag_errors) - 1 >= 2
    assert all(bag_errors.get(m) == d for m, d in page_errors.items())
    drawn = sorted(tuple(round(v, 9) for v in rect[:4]) for rect in view["regions"]["rects"])
    assert any(drawn == sorted(tuple(round(float(v), 9) for v in (*r.lower, *r.upper))
                               for r in snapshot.leaves) for snapshot in run.region_map)
    assert view["goal"] is not None and all(-1 <= v <= 1 for v in view["goal"])
    # The page's picture was the run's: every landing of the bag was drawn.
    landed_in_bag = sum(m.status == Movement.STATUS_OK for m in run.movements)
    assert stats["landings"] == landed_in_bag
    assert stats["updates"] > 20
