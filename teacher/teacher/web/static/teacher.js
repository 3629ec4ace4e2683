// The web teacher's page: polls /api/state with cursors of what it already drew, and draws
// only what changed: new landings onto their own canvas (never redrawn during a run), the
// region tree onto the base canvas when its version moves, goals on a small overlay when a
// goal moved; texts are written only when they change (each write costs the browser a layout).
// window.teacherStats says how long each update took (benchmarks/bench_web_teacher.py).
"use strict";
(() => {
  const POLL_MS = 300;  // about 3 updates a second (each waits for the previous answer)
  const token = new URLSearchParams(location.search).get("token") || "";
  const auth = token ? { "X-Teacher-Token": token } : {};
  const withToken = (url) => (token ? `${url}${url.includes("?") ? "&" : "?"}token=${encodeURIComponent(token)}` : url);
  const $ = (id) => document.getElementById(id);
  const W = $("base").width, H = $("base").height;
  const base = $("base").getContext("2d");
  const land = $("landings").getContext("2d");
  const over = $("overlay").getContext("2d");
  const errorCanvas = $("errors").getContext("2d");

  const cursor = { landings: 0, evaluations: 0, regions: -1, teaching: -1, log: 0 };
  const view = { legend: null, lake: null, regions: null, teaching: null, goal: null,
                 evaluations: [], count: 0, total: 0, offer: null, castVersion: 0, over: false };
  const stats = { updates: 0, totalMs: 0, maxMs: 0, lastMs: 0, slow: 0, landings: 0,
                  failures: 0, started: performance.now() };
  window.teacherStats = stats;

  const shown = new Map();  // element id -> text on screen
  const setText = (id, text) => {
    const value = String(text);
    if (shown.get(id) !== value) { shown.set(id, value); $(id).textContent = value; }
  };
  const setClass = (id, name) => { if ($(id).className !== name) $(id).className = name; };
  let overlayKey = "";

  const px = (x) => ((x + 1) / 2) * W;
  const py = (y) => ((1 - y) / 2) * H;
  const rgb = (c, a = 1) => `rgba(${c[0]},${c[1]},${c[2]},${a})`;

  function interestColour(f) {
    const stops = view.legend.interest;
    f = Math.min(1, Math.max(0, f || 0));
    for (let i = 1; i < stops.length; i++) {
      const [f0, c0] = stops[i - 1], [f1, c1] = stops[i];
      if (f <= f1) {
        const t = (f - f0) / (f1 - f0);
        return c0.map((v, k) => Math.round(v + t * (c1[k] - v)));
      }
    }
    return stops[stops.length - 1][1];
  }

  // --- drawing -------------------------------------------------------------------------

  function drawBase() {
    base.clearRect(0, 0, W, H);
    if (view.lake) base.drawImage(view.lake, 0, 0, W, H);
    const regions = view.regions;
    if (regions && regions.rects.length) {
      for (const [x0, y0, x1, y1, interest] of regions.rects) {
        const f = regions.top > 0 ? interest / regions.top : 0;
        base.fillStyle = rgb(interestColour(f), 0.28);
        base.fillRect(px(x0), py(y1), px(x1) - px(x0), py(y0) - py(y1));
      }
      base.strokeStyle = "rgba(60,60,60,0.45)";
      base.lineWidth = 1;
      for (const [x0, y0, x1, y1] of regions.rects) {
        base.strokeRect(px(x0) + 0.5, py(y1) + 0.5, px(x1) - px(x0), py(y0) - py(y1));
      }
    }
    base.strokeStyle = "rgba(0,0,0,0.15)";
    base.beginPath();
    base.moveTo(W / 2, 0); base.lineTo(W / 2, H); base.moveTo(0, H / 2); base.lineTo(W, H / 2);
    base.stroke();
  }

  function drawLandings(batch) {
    if (batch.from === 0 && stats.landings > 0) {
      land.clearRect(0, 0, W, H);  // the node restarted: start again
      stats.landings = 0;
    }
    const procs = view.legend.processes;
    let style = "";
    for (let i = 0; i < batch.x.length; i++) {
      const colour = procs[batch.p[i]] ? procs[batch.p[i]].rgb : [120, 120, 120];
      const next = rgb(colour, 0.85);
      if (next !== style) { land.fillStyle = next; style = next; }
      land.fillRect(px(batch.x[i]) - 1.5, py(batch.y[i]) - 1.5, 3, 3);
    }
    stats.landings = batch.from + batch.x.length;
  }

  function drawOverlay(force = false) {
    const key = JSON.stringify([view.goal, cursor.teaching, view.offer && view.offer.id]);
    if (key === overlayKey && !force) return;  // nothing on it moved
    overlayKey = key;
    over.clearRect(0, 0, W, H);
    const t = view.teaching;
    if (t) {
      over.font = "11px sans-serif";
      t.outcomes.forEach(([x, y], i) => {
        over.beginPath();
        over.arc(px(x), py(y), 6, 0, 2 * Math.PI);
        if (t.reached[i]) {  // a ring: reached goals must not hide the landings near them
          over.lineWidth = 2.5; over.strokeStyle = "rgba(20,150,40,0.95)"; over.stroke();
        } else {
          over.fillStyle = "rgba(230,40,40,0.9)"; over.fill();
          over.lineWidth = 1.5; over.strokeStyle = "#fff"; over.stroke();
        }
        over.fillStyle = "#111";
        over.fillText(String(i), px(x) + 8, py(y) - 6);
      });
    }
    if (view.goal) {
      const [x, y] = view.goal;
      over.beginPath();
      over.arc(px(x), py(y), 8, 0, 2 * Math.PI);
      over.lineWidth = 3; over.strokeStyle = "#000"; over.stroke();
      over.lineWidth = 1.5; over.strokeStyle = "#fff"; over.stroke();
    }
    if (view.offer) {
      const [gx, gy] = view.offer.goal, [ox, oy] = view.offer.outcome;
      over.setLineDash([4, 3]);
      over.strokeStyle = "#6a1b9a"; over.lineWidth = 1.5;
      over.beginPath(); over.moveTo(px(gx), py(gy)); over.lineTo(px(ox), py(oy)); over.stroke();
      over.setLineDash([]);
      over.beginPath(); over.arc(px(ox), py(oy), 9, 0, 2 * Math.PI); over.stroke();
      over.beginPath(); over.moveTo(px(gx) - 6, py(gy)); over.lineTo(px(gx) + 6, py(gy));
      over.moveTo(px(gx), py(gy) - 6); over.lineTo(px(gx), py(gy) + 6); over.stroke();
    }
  }

  function drawErrors() {
    const c = errorCanvas, w = c.canvas.width, h = c.canvas.height, m = 30;
    c.clearRect(0, 0, w, h);
    c.strokeStyle = "#888"; c.lineWidth = 1;
    c.strokeRect(m, 6, w - m - 6, h - m);
    const points = view.evaluations;
    c.fillStyle = "#555"; c.font = "11px sans-serif";
    if (!points.length) { c.fillText("no evaluation yet", m + 8, h / 2); return; }
    const xMax = Math.max(view.total || 0, points[points.length - 1][0], 1);
    const yMax = Math.max(...points.map((p) => p[1])) * 1.1 || 1;
    const X = (v) => m + (v / xMax) * (w - m - 6);
    const Y = (v) => 6 + (1 - v / yMax) * (h - m);
    c.fillText(yMax.toFixed(2), 2, 14); c.fillText("0", 18, h - m + 6);
    c.fillText(String(xMax), w - 40, h - 8); c.fillText("movements", m + 4, h - 8);
    c.strokeStyle = "#1f77b4"; c.lineWidth = 2; c.beginPath();
    points.forEach(([x, y], i) => (i ? c.lineTo(X(x), Y(y)) : c.moveTo(X(x), Y(y))));
    c.stroke();
    c.fillStyle = "#1f77b4";
    points.forEach(([x, y]) => c.fillRect(X(x) - 2, Y(y) - 2, 4, 4));
    const last = points[points.length - 1];
    c.fillStyle = "#222";
    c.fillText(`${last[1].toFixed(3)} at ${last[0]}`, w - 110, 20);
  }

  function drawLegend() {
    const box = $("legend");
    box.textContent = "";
    for (const code of Object.keys(view.legend.processes)) {
      const { name, rgb: colour } = view.legend.processes[code];
      const dot = document.createElement("span");
      dot.className = "dot"; dot.style.background = rgb(colour);
      box.append(dot, name);
    }
    const bar = document.createElement("canvas");
    bar.width = 80; bar.height = 10;
    const g = bar.getContext("2d");
    for (let i = 0; i < 80; i++) { g.fillStyle = rgb(interestColour(i / 79)); g.fillRect(i, 0, 1, 10); }
    const label = document.createElement("span");
    label.style.marginLeft = "12px";
    label.textContent = "interest: low";
    box.append(label, bar, "high · teaching goal: ");
    const red = document.createElement("span"); red.className = "dot"; red.style.background = "rgb(230,40,40)";
    const green = document.createElement("span"); green.className = "dot";
    green.style.border = "2px solid rgb(20,150,40)"; green.style.width = green.style.height = "7px";
    box.append(red, "unreached", green, "reached");
  }

  // --- the state ---------------------------------------------------------------------------

  function apply(s) {
    view.count = s.count; view.total = s.total; view.goal = s.goal;
    setText("learner", s.learner || "-");
    setText("count", s.count);
    setText("total", s.total || "?");
    const width = s.total ? `${Math.min(100, Math.floor((100 * s.count) / s.total))}%` : "0";
    if ($("progress-bar").style.width !== width) $("progress-bar").style.width = width;
    setText("failed", s.failed);
    setText("demos", s.demonstrations_given);
    if (s.landings.x.length || (s.landings.from === 0 && stats.landings > 0)) {
      drawLandings(s.landings);
    }
    cursor.landings = s.landings.from + s.landings.x.length;
    setText("landed", cursor.landings);
    if (s.regions) { view.regions = s.regions; cursor.regions = s.regions.version; drawBase(); }
    if (s.teaching) {
      view.teaching = s.teaching; cursor.teaching = s.teaching.version;
      setText("reached", s.teaching.reached.filter(Boolean).length);
      setText("teaching-total", s.teaching.reached.length);
    }
    if (s.evaluations.points.length) {
      view.evaluations = view.evaluations.slice(0, s.evaluations.from).concat(s.evaluations.points);
      drawErrors();
    }
    cursor.evaluations = view.evaluations.length;
    for (const [number, level, text] of s.log) {
      const li = document.createElement("li");
      li.className = level; li.textContent = text;
      $("log").prepend(li);
      cursor.log = number;
    }
    if (s.log.length) while ($("log").children.length > 200) $("log").lastChild.remove();
    showRun(s.run, s.pace);
    if (s.cast.version > view.castVersion) {
      view.castVersion = s.cast.version;
      $("cast").src = withToken(`/cast.gif?v=${s.cast.version}`);
      $("cast").classList.remove("hidden");
      setText("cast-caption", s.cast.caption);
    } else if (s.cast.rendering && !view.castVersion) {
      setText("cast-caption", "drawing the cast...");
    }
    drawOverlay();
  }

  function showRun(run, pace) {
    view.over = run.state === "finished" || run.state === "aborted";
    view.runState = run.state;
    setText("run-state", run.state === "waiting" ? "waiting for the run" : run.state);
    setClass("run-state", `badge${view.over ? " over" : ""}`);
    let text = "", kind = "";
    if (pace.waiting) {
      kind = "turn";
      text = pace.wait_left === null ? "your turn" : `your turn: ${Math.ceil(pace.wait_left)} s left`;
    } else if (pace.paused) {
      kind = "paused"; text = pace.held ? "paused" : "pausing...";
    } else if (pace.steps_left) {
      text = `stepping: ${pace.steps_left} left`;
    }
    setText("pace-state", text);
    setClass("pace-state", `badge ${kind}${text && !view.over ? "" : " hidden"}`);
    const disabled = view.over || !pace.known;
    for (const id of ["pause", "resume", "step"]) if ($(id).disabled !== disabled) $(id).disabled = disabled;
  }

  async function poll() {
    const query = new URLSearchParams(cursor).toString();
    try {
      const reply = await fetch(`/api/state?${query}`, { headers: auth, cache: "no-store" });
      if (!reply.ok) throw new Error(`${reply.status}`);
      const s = await reply.json();
      const t0 = performance.now();
      apply(s);
      const ms = performance.now() - t0;
      stats.updates += 1; stats.totalMs += ms; stats.lastMs = ms;
      stats.maxMs = Math.max(stats.maxMs, ms);
      if (ms > 50) stats.slow += 1;  // a frame a person would notice
      setTimeout(poll, POLL_MS);
    } catch (error) {
      stats.failures += 1;  // the badge says it; the message line keeps the last command's answer
      setText("run-state", view.over ? `${view.runState}: the web teacher has stopped`
                                     : `the web teacher does not answer (${error.message})`);
      setClass("run-state", "badge over");
      setTimeout(poll, 1000);
    }
  }

  // --- commands --------------------------------------------------------------------------

  function say(text, ok) {
    const m = $("message");
    m.textContent = text;
    m.className = ok ? "ok" : "error";
  }

  async function command(body) {
    if (view.over) {  // the node may be gone already: say it here
      say(`the run is over (${view.runState}): the learner takes no more demonstrations`, false);
      return { ok: false };
    }
    try {
      const reply = await fetch("/api/command", {
        method: "POST", body: JSON.stringify(body),
        headers: { ...auth, "Content-Type": "application/json", "X-Teacher": "1" },
      });
      const answer = await reply.json();
      say(answer.message, answer.ok);
      return answer;
    } catch (error) {
      say(`the command did not reach the web teacher: ${error.message}`, false);
      return { ok: false };
    }
  }

  function clickedPoint(event) {
    const box = $("overlay").getBoundingClientRect();
    const x = ((event.clientX - box.left) / box.width) * W;
    const y = ((event.clientY - box.top) / box.height) * H;
    return [x, y];
  }

  $("overlay").addEventListener("click", async (event) => {
    const [x, y] = clickedPoint(event);
    const t = view.teaching;
    if (t) {
      let best = -1, bestD = 10;
      t.outcomes.forEach(([gx, gy], i) => {
        const d = Math.hypot(px(gx) - x, py(gy) - y);
        if (d <= bestD && !t.reached[i]) { best = i; bestD = d; }
      });
      if (best >= 0) { await command({ command: "teach", index: best }); return; }
    }
    const goal = [Math.min(1, Math.max(-1, (x / W) * 2 - 1)), Math.min(1, Math.max(-1, 1 - (y / H) * 2))];
    const answer = await command({ command: "offer", x: goal[0], y: goal[1] });
    if (answer.ok && answer.offer) {
      view.offer = answer.offer;
      $("offer-text").textContent = answer.offer.text;
      $("offer").classList.remove("hidden");
    }
    drawOverlay(true);
  });

  function closeOffer() { view.offer = null; $("offer").classList.add("hidden"); drawOverlay(true); }
  $("confirm").addEventListener("click", async () => {
    if (!view.offer) return;
    const answer = await command({ command: "confirm", offer: view.offer.id });
    if (answer.ok) closeOffer();
  });
  $("cancel").addEventListener("click", closeOffer);
  $("pause").addEventListener("click", () => command({ command: "pace", what: "pause" }));
  $("resume").addEventListener("click", () => command({ command: "pace", what: "resume" }));
  $("step").addEventListener("click", () =>
    command({ command: "pace", what: "step", steps: Number($("step-count").value) || 1 }));
  $("send-action").addEventListener("click", () =>
    command({ command: "action", text: $("action-text").value }));

  // For tests and people with a console: where teaching goal i is drawn, in canvas pixels.
  window.teacherPage = {
    teachingPixel: (i) => ({ x: px(view.teaching.outcomes[i][0]), y: py(view.teaching.outcomes[i][1]) }),
    view, cursor,
  };

  async function start() {
    try {
      view.legend = await (await fetch("/api/legend", { headers: auth })).json();
    } catch (error) {
      say(`the web teacher does not answer: ${error.message}`, false);
      setTimeout(start, 1000);
      return;
    }
    drawLegend();
    const lake = new Image();
    lake.onload = () => { view.lake = lake; drawBase(); };
    lake.src = withToken("/lake.png");
    drawBase(); drawErrors();
    poll();
  }
  start();
})();
