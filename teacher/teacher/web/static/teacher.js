// The web teacher's page: polls /api/state with cursors of what it already drew, and draws
// only what changed: new landings onto their own canvas (never redrawn during a run), the
// region tree onto the base canvas when its version moves, goals on a small overlay when a
// goal moved; texts are written only when they change (each write costs the browser a layout).
// window.teacherStats says how long each update took (benchmarks/bench_web_teacher.py).
//
// One command at a time: every command button is disabled until the answer comes, and each
// demonstration request carries a new idempotency key, so a double click or a retry cannot
// demonstrate twice. The legend lists exactly the marks on the picture (teacherPage.drawn).
// The map's axes and the error chart are SVG, in metres of the world (the legend's "space":
// the box the outcome space [-1, 1]^2 maps onto). A refused request shows the server's own
// message (a missing token: which address to open).
"use strict";
(() => {
  const POLL_MS = 300;  // about 3 updates a second (each waits for the previous answer)
  const PICK_PX = 10;  // a click this near a teaching goal picks it
  const SHADE_ALPHA = 0.22;  // interest over the lake: land and water stay apart under it
  const token = new URLSearchParams(location.search).get("token") || "";
  const auth = token ? { "X-Teacher-Token": token } : {};
  const withToken = (url) => (token ? `${url}${url.includes("?") ? "&" : "?"}token=${encodeURIComponent(token)}` : url);
  // crypto.randomUUID needs a secure context, which http:// on another machine is not.
  const newKey = () => Array.from(crypto.getRandomValues(new Uint8Array(16)),
                                  (b) => b.toString(16).padStart(2, "0")).join("");
  const $ = (id) => document.getElementById(id);
  const W = $("base").width, H = $("base").height;
  const base = $("base").getContext("2d");
  const land = $("landings").getContext("2d");
  const over = $("overlay").getContext("2d");
  const SVG = "http://www.w3.org/2000/svg";

  const cursor = { landings: 0, evaluations: 0, regions: -1, teaching: -1, log: 0 };
  const view = { legend: null, lake: null, shore: null, surface: null, regions: null,
                 teaching: null, goal: null, demonstrations: [], evaluations: [], count: 0,
                 total: 0, offer: null, castVersion: 0, over: false, runState: "waiting",
                 linger: { left: null, closed: false }, paceKnown: false, busy: false,
                 gone: false };
  const stats = { updates: 0, totalMs: 0, maxMs: 0, lastMs: 0, slow: 0, landings: 0,
                  failures: 0, started: performance.now() };
  window.teacherStats = stats;
  // What is on the picture now, by legend entry: the legend shows these and only these.
  const drawn = { processes: new Set(), base: new Set(), overlay: new Set() };
  let legendKey = "";

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
  const mark = (name) => view.legend.marks[name];

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

  // --- the lake: its land and water, and the shore drawn over the shading ----------------

  function readLake(image) {
    const c = document.createElement("canvas");
    c.width = image.width; c.height = image.height;
    const g = c.getContext("2d");
    g.drawImage(image, 0, 0);
    const pixels = g.getImageData(0, 0, c.width, c.height);
    const w = c.width, h = c.height, wet = new Uint8Array(w * h);
    for (let i = 0; i < w * h; i++) wet[i] = pixels.data[4 * i + 2] > pixels.data[4 * i] ? 1 : 0;
    const shore = g.createImageData(w, h);
    for (let y = 0; y < h; y++) {
      for (let x = 0; x < w; x++) {
        const i = y * w + x;
        if ((x + 1 < w && wet[i] !== wet[i + 1]) || (y + 1 < h && wet[i] !== wet[i + w])) {
          shore.data.set([...mark("shore"), 255], 4 * i);
        }
      }
    }
    g.putImageData(shore, 0, 0);
    view.surface = { wet, w, h };
    return c;
  }

  // --- drawing -------------------------------------------------------------------------

  function drawBase() {
    base.clearRect(0, 0, W, H);
    drawn.base.clear();
    if (view.lake) {
      base.drawImage(view.lake, 0, 0, W, H);
      drawn.base.add("water").add("land");
    }
    const regions = view.regions;
    if (regions && regions.rects.length) {
      for (const [x0, y0, x1, y1, interest] of regions.rects) {
        const f = regions.top > 0 ? interest / regions.top : 0;
        base.fillStyle = rgb(interestColour(f), SHADE_ALPHA);
        base.fillRect(px(x0), py(y1), px(x1) - px(x0), py(y0) - py(y1));
      }
      base.strokeStyle = "rgba(60,60,60,0.45)";
      base.lineWidth = 1;
      for (const [x0, y0, x1, y1] of regions.rects) {
        base.strokeRect(px(x0) + 0.5, py(y1) + 0.5, px(x1) - px(x0), py(y0) - py(y1));
      }
      drawn.base.add("interest");
    }
    if (view.shore) {  // over the shading: the coast stays sharp whatever the interest
      base.imageSmoothingEnabled = false;
      base.drawImage(view.shore, 0, 0, W, H);
      base.imageSmoothingEnabled = true;
      drawn.base.add("shore");
    }
    base.strokeStyle = "rgba(0,0,0,0.15)";
    base.beginPath();
    base.moveTo(W / 2, 0); base.lineTo(W / 2, H); base.moveTo(0, H / 2); base.lineTo(W, H / 2);
    base.stroke();
    drawLegend();
  }

  function drawLandings(batch) {
    if (batch.from === 0 && stats.landings > 0) {
      land.clearRect(0, 0, W, H);  // the node restarted: start again
      stats.landings = 0;
      drawn.processes.clear();
    }
    const procs = view.legend.processes;
    let style = "";
    for (let i = 0; i < batch.x.length; i++) {
      const code = String(batch.p[i]);
      const colour = procs[code] ? procs[code].rgb : [120, 120, 120];
      drawn.processes.add(procs[code] ? code : "other");
      const next = rgb(colour, 0.85);
      if (next !== style) { land.fillStyle = next; style = next; }
      land.fillRect(px(batch.x[i]) - 1.5, py(batch.y[i]) - 1.5, 3, 3);
    }
    stats.landings = batch.from + batch.x.length;
  }

  function drawOverlay(force = false) {
    const demos = view.demonstrations;
    const key = JSON.stringify([view.goal, cursor.teaching, view.offer && view.offer.id,
                                demos.length && demos[demos.length - 1].index]);
    if (key === overlayKey && !force) return;  // nothing on it moved
    overlayKey = key;
    over.clearRect(0, 0, W, H);
    drawn.overlay.clear();
    const t = view.teaching;
    if (t) {
      over.font = "11px sans-serif";
      t.outcomes.forEach(([x, y], i) => {
        over.beginPath();
        over.arc(px(x), py(y), 6, 0, 2 * Math.PI);
        if (t.reached[i]) {  // a ring: reached goals must not hide the landings near them
          over.lineWidth = 2.5; over.strokeStyle = rgb(mark("reached"), 0.95); over.stroke();
          drawn.overlay.add("reached");
        } else {
          over.fillStyle = rgb(mark("unreached"), 0.9); over.fill();
          over.lineWidth = 1.5; over.strokeStyle = "#fff"; over.stroke();
          drawn.overlay.add("unreached");
        }
        over.fillStyle = "#111";
        over.fillText(String(i), px(x) + 8, py(y) - 6);
      });
    }
    for (const d of demos) {  // what the teacher showed: a diamond at its outcome
      if (!d.outcome || d.outcome.length !== 2) continue;
      const [x, y] = [px(d.outcome[0]), py(d.outcome[1])];
      over.beginPath();
      over.moveTo(x, y - 7); over.lineTo(x + 7, y); over.lineTo(x, y + 7); over.lineTo(x - 7, y);
      over.closePath();
      over.lineWidth = 2; over.strokeStyle = rgb(mark("demonstration")); over.stroke();
      drawn.overlay.add("demonstration");
    }
    if (view.goal) {
      const [x, y] = view.goal;
      over.beginPath();
      over.arc(px(x), py(y), 8, 0, 2 * Math.PI);
      over.lineWidth = 3; over.strokeStyle = rgb(mark("goal")); over.stroke();
      over.lineWidth = 1.5; over.strokeStyle = "#fff"; over.stroke();
      drawn.overlay.add("goal");
    }
    if (view.offer) {
      const [gx, gy] = view.offer.goal, [ox, oy] = view.offer.outcome;
      over.setLineDash([4, 3]);
      over.strokeStyle = rgb(mark("offer")); over.lineWidth = 1.5;
      over.beginPath(); over.moveTo(px(gx), py(gy)); over.lineTo(px(ox), py(oy)); over.stroke();
      over.setLineDash([]);
      over.beginPath(); over.arc(px(ox), py(oy), 9, 0, 2 * Math.PI); over.stroke();
      over.beginPath(); over.moveTo(px(gx) - 6, py(gy)); over.lineTo(px(gx) + 6, py(gy));
      over.moveTo(px(gx), py(gy) - 6); over.lineTo(px(gx), py(gy) + 6); over.stroke();
      drawn.overlay.add("offer");
    }
    drawLegend();
  }

  // --- axes: the map's and the error chart's, in metres ------------------------------------

  // Round tick values from lo to hi, about `count` of them (steps of 1, 2 or 5 x 10^k).
  function ticks(lo, hi, count) {
    const span = hi - lo;
    if (!(span > 0)) return [lo];
    const raw = span / count, size = 10 ** Math.floor(Math.log10(raw));
    const step = [1, 2, 5, 10].map((f) => f * size).find((v) => v >= raw * 0.999);
    const out = [];
    for (let k = Math.ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * span; k++) {
      out.push(Number((k * step).toPrecision(12)));
    }
    return out;
  }
  const label = (v) => String(Number(v.toPrecision(6)));

  function svg(parent, name, attrs = {}, text = undefined) {
    const e = document.createElementNS(SVG, name);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    if (text !== undefined) e.textContent = text;
    parent.append(e);
    return e;
  }

  // Metres of the world, from an outcome coordinate (u in [-1, 1]) and back.
  const space = () => view.legend.space;
  const metres = (u, axis) => { const b = space().box, lo = b[2 * axis], hi = b[2 * axis + 1];
                                return lo + ((u + 1) / 2) * (hi - lo); };
  const outcome = (m, axis) => { const b = space().box, lo = b[2 * axis], hi = b[2 * axis + 1];
                                 return (2 * (m - lo)) / (hi - lo) - 1; };
  // An outcome distance in metres (the box is square: one scale for x and y).
  const distanceMetres = (d) => (d * (space().box[1] - space().box[0])) / 2;

  function drawMapAxes() {
    const s = space(), unit = s.unit, xs = $("x-axis"), ys = $("y-axis");
    xs.textContent = ""; ys.textContent = "";
    const yw = Number(ys.getAttribute("width"));
    for (const v of ticks(s.box[0], s.box[1], 10)) {  // 1 px: the map's border
      const x = 1 + px(outcome(v, 0));
      svg(xs, "line", { x1: x, x2: x, y1: 0, y2: 5, class: "tick" });
      svg(xs, "text", { x, y: 17, "text-anchor": "middle", class: "tick-label",
                        "data-value": v }, label(v));
    }
    svg(xs, "text", { x: 301, y: 34, "text-anchor": "middle", class: "title" },
        `x (${unit}), ${s.x}`);
    for (const v of ticks(s.box[2], s.box[3], 10)) {
      const y = 1 + py(outcome(v, 1));
      svg(ys, "line", { x1: yw - 5, x2: yw, y1: y, y2: y, class: "tick" });
      svg(ys, "text", { x: yw - 8, y: y + 4, "text-anchor": "end", class: "tick-label",
                        "data-value": v }, label(v));
    }
    svg(ys, "text", { x: 0, y: 0, "text-anchor": "middle", class: "title",
                      transform: "translate(12 301) rotate(-90)" }, `y (${unit}), ${s.y}`);
    const scale = distanceMetres(1);
    setText("map-caption", `Seen from above, the robot at (0, 0): where the hook lands, in `
            + `${unit === "m" ? "metres" : unit} of the world. Offers and the teaching goals' `
            + `list give the learner's outcome coordinates, from -1 to 1: these divided by `
            + `${label(scale)}.`);
  }

  function drawErrors() {
    const chart = $("errors"), w = Number(chart.getAttribute("width"));
    const h = Number(chart.getAttribute("height"));
    const left = 46, right = 10, top = 10, bottom = 36;
    const unit = space().unit;
    chart.textContent = "";
    svg(chart, "rect", { x: left, y: top, width: w - left - right, height: h - top - bottom,
                         fill: "none", stroke: "#888" });
    svg(chart, "text", { x: (left + w - right) / 2, y: h - 4, "text-anchor": "middle",
                         class: "title" }, "movements");
    svg(chart, "text", { x: 0, y: 0, "text-anchor": "middle", class: "title",
                         transform: `translate(12 ${(top + h - bottom) / 2}) rotate(-90)` },
        `error (${unit})`);
    const points = view.evaluations;
    if (!points.length) {
      svg(chart, "text", { x: left + 10, y: top + 20 }, "no evaluation yet");
      return;
    }
    const ms = points.map(([x, y]) => [x, distanceMetres(y)]);
    const xMax = Math.max(view.total || 0, ms[ms.length - 1][0], 1);
    // The y axis ends at the first round tick above the largest error: every point inside.
    const highest = Math.max(...ms.map((p) => p[1])) * 1.05 || 1;
    const rough = ticks(0, highest, 4), step = rough[1] - rough[0] || highest;
    const yTicks = Array.from({ length: Math.ceil(highest / step - 1e-9) + 1 },
                              (_, k) => Number((k * step).toPrecision(12)));
    const yMax = yTicks[yTicks.length - 1];
    const X = (v) => left + (v / xMax) * (w - left - right);
    const Y = (v) => top + (1 - v / yMax) * (h - top - bottom);
    for (const v of ticks(0, xMax, 4)) {
      svg(chart, "line", { x1: X(v), x2: X(v), y1: h - bottom, y2: h - bottom + 4, class: "tick" });
      svg(chart, "text", { x: X(v), y: h - bottom + 15, "text-anchor": "middle",
                           class: "tick-label x", "data-value": v }, label(v));
    }
    for (const v of yTicks) {
      if (v > 0) svg(chart, "line", { x1: left, x2: w - right, y1: Y(v), y2: Y(v), class: "grid" });
      svg(chart, "text", { x: left - 4, y: Y(v) + 4, "text-anchor": "end",
                           class: "tick-label y", "data-value": v }, label(v));
    }
    svg(chart, "polyline", { class: "curve",
                             points: ms.map(([x, y]) => `${X(x)},${Y(y)}`).join(" ") });
    for (const [x, y] of ms) {
      svg(chart, "circle", { cx: X(x), cy: Y(y), r: 2.5, class: "point", "data-movement": x,
                             "data-value": y });
    }
    const [lx, ly] = ms[ms.length - 1];
    svg(chart, "text", { x: w - right - 4, y: top + 14, "text-anchor": "end", class: "latest" },
        `${ly.toFixed(2)} ${unit} at movement ${lx}`);
  }

  // --- the legend: one entry per kind of mark on the picture, no more ----------------------

  function swatch(kind, colour) {
    const s = document.createElement("span");
    s.className = `swatch ${kind}`;
    if (kind === "ring") s.style.borderColor = rgb(colour);
    else if (kind === "diamond") s.style.borderColor = rgb(colour);
    else if (kind === "dashed") s.style.borderColor = rgb(colour);
    else s.style.background = rgb(colour);
    return s;
  }

  function entry(id, colour, label, kind = "dot") {
    const e = document.createElement("span");
    e.className = "entry"; e.dataset.mark = id;
    if (colour) { e.dataset.rgb = colour.join(","); e.append(swatch(kind, colour)); }
    e.append(label);
    return e;
  }

  function legendMarks() {
    const marks = [...[...drawn.processes].sort().map((c) => `landing-${c}`), ...drawn.base,
                   ...drawn.overlay];
    return [...new Set(marks)];
  }

  function drawLegend() {
    if (!view.legend) return;
    const marks = legendMarks();
    const key = marks.join(" ");
    if (key === legendKey) return;
    legendKey = key;
    const box = $("legend");
    box.textContent = "";
    const procs = view.legend.processes;
    const landings = marks.filter((m) => m.startsWith("landing-"));
    if (landings.length) {
      const group = document.createElement("span"); group.className = "group";
      group.append("landings:");
      for (const m of landings) {
        const code = m.slice("landing-".length);
        group.append(procs[code] ? entry(m, procs[code].rgb, procs[code].name)
                                 : entry(m, [120, 120, 120], "other"));
      }
      box.append(group);
    }
    const other = document.createElement("span"); other.className = "group";
    const lake = view.legend.lake;
    if (marks.includes("water")) other.append(entry("water", lake.water, "water", "square"));
    if (marks.includes("land")) other.append(entry("land", lake.land, "land", "square"));
    if (marks.includes("shore")) other.append(entry("shore", mark("shore"), "shore", "line"));
    if (marks.includes("interest")) {
      const e = entry("interest", null, "interest regions: low ");
      const bar = document.createElement("canvas");
      bar.width = 80; bar.height = 10;
      const g = bar.getContext("2d");
      for (let i = 0; i < 80; i++) { g.fillStyle = rgb(interestColour(i / 79)); g.fillRect(i, 0, 1, 10); }
      e.append(bar, " high");
      other.append(e);
    }
    if (other.childNodes.length) box.append(other);
    const goals = document.createElement("span"); goals.className = "group";
    if (marks.includes("unreached")) goals.append(entry("unreached", mark("unreached"), "teaching goal, unreached"));
    if (marks.includes("reached")) goals.append(entry("reached", mark("reached"), "teaching goal, reached", "ring"));
    if (marks.includes("demonstration")) goals.append(entry("demonstration", mark("demonstration"), "demonstrated outcome", "diamond"));
    if (marks.includes("goal")) goals.append(entry("goal", mark("goal"), "learner's current goal", "ring"));
    if (marks.includes("offer")) goals.append(entry("offer", mark("offer"), "offer: goal to outcome", "dashed"));
    if (goals.childNodes.length) box.append(goals);
  }

  // --- the state ---------------------------------------------------------------------------

  function showProblem(text) {
    setText("problem", text);
    $("problem").classList.toggle("hidden", !text);
  }

  // The server's own words on a refused request (they say what is wrong and what to do).
  async function failure(reply) {
    let why = `HTTP ${reply.status}`;
    try {
      const answer = await reply.json();
      if (answer && answer.message) why = answer.message;
    } catch (error) { /* not JSON: its status says it */ }
    return Object.assign(new Error(why), { status: reply.status });
  }

  // A refusal only another address mends (no or a wrong token, an unknown host): said once,
  // and the page stops asking.
  function noAccess(error) {
    if (error.status !== 401 && error.status !== 403) return false;
    showProblem(error.message);
    setText("run-state", "no access: see the message below");
    setClass("run-state", "badge over");
    return true;
  }

  function apply(s) {
    view.count = s.count; view.total = s.total; view.goal = s.goal;
    view.demonstrations = s.demonstrations || [];
    setText("learner", s.learner || "-");
    if (s.learner_title) {
      const title = `${s.learner_title} web teacher`;
      setText("title", title);
      if (document.title !== title) document.title = title;
    }
    setText("count", s.count);
    setText("total", s.total || "?");
    const width = s.total ? `${Math.min(100, Math.floor((100 * s.count) / s.total))}%` : "0";
    if ($("progress-bar").style.width !== width) $("progress-bar").style.width = width;
    setText("failed", s.failed);
    setText("demos", s.demonstrations_given);
    $("requests").classList.toggle("hidden", !s.expert);
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
    view.linger = s.linger || { left: null, closed: false };
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

  function refreshButtons() {
    const pace = view.busy || view.over || !view.paceKnown;
    for (const id of ["pause", "resume", "step"]) if ($(id).disabled !== pace) $(id).disabled = pace;
    const demonstrate = view.busy || view.over;
    for (const b of document.querySelectorAll("button.demonstrate")) {
      if (b.disabled !== demonstrate) b.disabled = demonstrate;
    }
    const close = view.busy || view.gone || view.linger.closed;
    if ($("close").disabled !== close) $("close").disabled = close;
    $("space").classList.toggle("busy", view.busy);
  }

  function showOver() {
    if (!view.over) { $("over").classList.add("hidden"); return; }
    $("over").classList.remove("hidden");
    const left = view.linger.left;
    let text;
    if (view.gone || view.linger.closed) {
      text = "The web teacher has stopped: this page shows the run as it ended.";
    } else if (left !== null) {
      text = `This page keeps showing it for ${Math.ceil(left)} s more, or until you close it.`;
    } else {
      text = "The web teacher stops with the run: this page keeps what it shows.";
    }
    setText("over-title", `The run is over (${view.runState} at movement ${view.count}).`);
    setText("over-text", text);
    $("close").classList.toggle("hidden", left === null || view.gone || view.linger.closed);
  }

  function showRun(run, pace) {
    view.over = run.state === "finished" || run.state === "aborted";
    view.runState = run.state;
    view.paceKnown = pace.known;
    setText("run-state", run.state === "waiting" ? "waiting for the run"
                         : view.over ? `${run.state}: the run is over` : run.state);
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
    showOver();
    refreshButtons();
  }

  async function poll() {
    const query = new URLSearchParams(cursor).toString();
    try {
      const reply = await fetch(`/api/state?${query}`, { headers: auth, cache: "no-store" });
      if (!reply.ok) throw await failure(reply);
      const s = await reply.json();
      showProblem("");
      const t0 = performance.now();
      apply(s);
      const ms = performance.now() - t0;
      stats.updates += 1; stats.totalMs += ms; stats.lastMs = ms;
      stats.maxMs = Math.max(stats.maxMs, ms);
      if (ms > 50) stats.slow += 1;  // a frame a person would notice
      setTimeout(poll, POLL_MS);
    } catch (error) {
      stats.failures += 1;  // the badge says it; the message line keeps the last command's answer
      if (noAccess(error)) return;
      if (error.status) showProblem(error.message);
      if (view.over) {
        view.gone = true;
        setText("run-state", `${view.runState}: the web teacher has stopped`);
        showOver(); refreshButtons();
      } else {
        setText("run-state", error.status ? `the web teacher refuses (${error.status})`
                             : `the web teacher does not answer (${error.message})`);
      }
      setClass("run-state", "badge over");
      setTimeout(poll, view.over ? 5000 : 1000);
    }
  }

  // --- commands --------------------------------------------------------------------------

  function say(text, ok) {
    const m = $("message");
    m.textContent = text;
    m.className = ok ? "ok" : "error";
  }

  // One command at a time; the buttons stay disabled until its answer comes.
  async function command(body) {
    if (view.busy) return { ok: false, busy: true };
    if (view.over && body.command !== "close") {  // the node may be gone already: say it here
      say(`the run is over (${view.runState}): the learner takes no more demonstrations`, false);
      return { ok: false };
    }
    view.busy = true; refreshButtons();
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
    } finally {
      view.busy = false; refreshButtons();
    }
  }

  const demonstrate = (body) => command({ ...body, key: newKey() });

  function clickedPoint(event) {
    const box = $("overlay").getBoundingClientRect();
    const x = ((event.clientX - box.left) / box.width) * W;
    const y = ((event.clientY - box.top) / box.height) * H;
    return [x, y];
  }

  function goalsNear(x, y) {
    const t = view.teaching;
    if (!t) return [];
    return t.outcomes.map(([gx, gy], i) => ({ i, d: Math.hypot(px(gx) - x, py(gy) - y) }))
      .filter((g) => g.d <= PICK_PX).sort((a, b) => a.d - b.d).map((g) => g.i);
  }

  function closePick() { $("pick").classList.add("hidden"); $("pick-list").textContent = ""; }

  // Several goals under the click, or one already reached: the person picks on purpose.
  function openPick(indices) {
    const t = view.teaching, list = $("pick-list");
    list.textContent = "";
    for (const i of indices) {
      const [x, y] = t.outcomes[i];
      const li = document.createElement("li");
      const b = document.createElement("button");
      b.type = "button"; b.className = "demonstrate"; b.dataset.index = String(i);
      b.textContent = t.reached[i] ? `Demonstrate entry ${i} again` : `Demonstrate entry ${i}`;
      b.addEventListener("click", async () => {
        const answer = await demonstrate({ command: "teach", index: i });
        if (answer.ok) closePick();
      });
      li.append(b, ` (${x >= 0 ? "+" : ""}${x.toFixed(3)}, ${y >= 0 ? "+" : ""}${y.toFixed(3)}) `
                   + (t.reached[i] ? "reached already" : "not reached"));
      list.append(li);
    }
    $("pick").classList.remove("hidden");
    refreshButtons();
  }

  $("overlay").addEventListener("click", async (event) => {
    // The answer to the last click is not in yet; or this is a double click's second click
    // (event.detail counts them), which a fast answer would otherwise let through.
    if (view.busy || event.detail > 1) return;
    const [x, y] = clickedPoint(event);
    const near = goalsNear(x, y);
    if (near.length === 1 && !view.teaching.reached[near[0]]) {
      closePick();
      await demonstrate({ command: "teach", index: near[0] });
      return;
    }
    if (near.length) { openPick(near); return; }
    closePick();
    const goal = [Math.min(1, Math.max(-1, (x / W) * 2 - 1)), Math.min(1, Math.max(-1, 1 - (y / H) * 2))];
    const answer = await command({ command: "offer", x: goal[0], y: goal[1] });
    if (answer.ok && answer.offer) {
      view.offer = { ...answer.offer, key: newKey() };  // one key per offer: confirmed once
      $("offer-text").textContent = answer.offer.text;
      $("offer").classList.remove("hidden");
    }
    drawOverlay(true);
  });

  function closeOffer() { view.offer = null; $("offer").classList.add("hidden"); drawOverlay(true); }
  $("confirm").addEventListener("click", async () => {
    if (!view.offer) return;
    const answer = await command({ command: "confirm", offer: view.offer.id, key: view.offer.key });
    if (answer.ok) closeOffer();
  });
  $("cancel").addEventListener("click", closeOffer);
  $("pick-cancel").addEventListener("click", closePick);
  $("pause").addEventListener("click", () => command({ command: "pace", what: "pause" }));
  $("resume").addEventListener("click", () => command({ command: "pace", what: "resume" }));
  $("step").addEventListener("click", () =>
    command({ command: "pace", what: "step", steps: Number($("step-count").value) || 1 }));
  $("none-there").addEventListener("click", () => command({ command: "none" }));
  $("send-action").addEventListener("click", () =>
    demonstrate({ command: "action", text: $("action-text").value }));
  $("close").addEventListener("click", async () => {
    const answer = await command({ command: "close" });
    if (answer.ok) { view.linger = { left: null, closed: true }; showOver(); refreshButtons(); }
  });

  // For tests and people with a console: where teaching goal i is drawn, in canvas pixels;
  // the marks drawn and the legend's; land or water under a canvas pixel.
  window.teacherPage = {
    teachingPixel: (i) => ({ x: px(view.teaching.outcomes[i][0]), y: py(view.teaching.outcomes[i][1]) }),
    drawn: () => legendMarks(),
    legend: () => [...document.querySelectorAll("#legend .entry")].map(
      (e) => ({ mark: e.dataset.mark, rgb: e.dataset.rgb ? e.dataset.rgb.split(",").map(Number) : null })),
    surfaceAt: (x, y) => {
      const s = view.surface;
      if (!s) return null;
      const i = Math.min(s.h - 1, Math.floor((y / H) * s.h)) * s.w + Math.min(s.w - 1, Math.floor((x / W) * s.w));
      return s.wet[i] ? "water" : "land";
    },
    view, cursor,
  };

  async function start() {
    try {
      const reply = await fetch("/api/legend", { headers: auth });
      if (!reply.ok) throw await failure(reply);
      view.legend = await reply.json();
    } catch (error) {
      if (noAccess(error)) return;
      if (error.status) {
        showProblem(error.message);
        setText("run-state", `the web teacher refuses (${error.status})`);
        setClass("run-state", "badge over");
      } else {
        say(`the web teacher does not answer: ${error.message}`, false);
      }
      setTimeout(start, 1000);
      return;
    }
    showProblem("");
    drawMapAxes();
    const lake = new Image();
    lake.onload = () => { view.lake = lake; view.shore = readLake(lake); drawBase(); };
    lake.src = withToken("/lake.png");
    drawBase(); drawErrors(); refreshButtons();
    poll();
  }
  start();
})();
