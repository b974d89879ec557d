// crashsim live: the page. It draws what the server sends and sends the values the user sets;
// every number of the physics comes from the server (crashsim's own code), none is computed here.
"use strict";
(function () {
  const NS = "http://www.w3.org/2000/svg";
  const COLOURS = [["#1f5fa8", "#cfe0f5"], ["#c0580a", "#fbe0c8"], ["#2a8a3a", "#d3efd6"], ["#7a3fa0", "#e8d8f2"],
                   ["#8a6d00", "#f3e8b8"]];
  const EVIDENCE = "#c2185b";
  const token = new URLSearchParams(location.search).get("token") || "";
  const $ = (id) => document.getElementById(id);
  const svg = $("scene");

  // -- state --------------------------------------------------------------------------------------
  let S = null;            // the static payload
  let R = null;            // the last good result
  let band = null;         // the last band
  let controls = {};       // path -> control (unit, per_si, ...)
  let values = {};         // path -> value as the file holds it: the page's truth
  let seq = 0, lastSent = 0, lastShown = -1;
  let view = null;         // {x, y, w, h}: world window (y up)
  let tIndex = 0, playing = false;
  const undo = [], redo = [];
  // measurement hooks (benchmarks/live_view.py): input time and drawn time of each change
  const probe = window.__live = {inputT: {}, drawnT: {}, lastDrawn: -1, lastSent: 0, lastAnswered: -1, lastInput: 0, busy: false, results: 0, invalid: 0, errors: 0,
                                 bands: 0, lastBand: null, messages: []};

  // -- the socket ---------------------------------------------------------------------------------
  let ws = null;
  function connect() {
    const proto = location.protocol === "https:" ? "wss" : "ws";
    ws = new WebSocket(`${proto}://${location.host}/ws?token=${encodeURIComponent(token)}`);
    ws.onopen = () => status("connected");
    ws.onclose = () => { status("disconnected: reload the page", "bad"); };
    ws.onmessage = (ev) => onMessage(JSON.parse(ev.data));
  }
  function send(msg) { if (ws && ws.readyState === 1) ws.send(JSON.stringify(msg)); }
  function status(text, cls) { const s = $("status"); s.textContent = text; s.className = "status " + (cls || ""); }

  // One change in flight at a time: a change made meanwhile waits, and only the latest waiting one
  // is sent when the answer comes (never a backlog). Inputs are counted: the probe times each input
  // from its event to the result that includes it drawn.
  let inputs = 0, inFlight = null, dirty = false;
  const upTo = {};
  function sendValues(inputTime) {
    inputs += 1;
    probe.lastInput = inputs;
    probe.inputT[inputs] = inputTime === undefined ? performance.now() : inputTime;
    dirty = true;
    probe.busy = true;
    if (inFlight === null) flush();
  }
  function flush() {
    seq += 1;
    lastSent = seq;
    probe.lastSent = seq;
    upTo[seq] = inputs;
    inFlight = seq;
    dirty = false;
    send({type: "set", seq: seq, values: Object.assign({}, values)});
    status("computing…", "busy");
  }
  function answered(s) {
    if (s !== inFlight) return;
    inFlight = null;
    if (dirty) flush(); else probe.busy = false;
  }

  function onMessage(m) {
    switch (m.type) {
      case "static": S = m; setupStatic(); break;
      case "result": onResult(m); break;
      case "invalid": onInvalid(m); break;
      case "band": onBand(m); break;
      case "saved": banner(`saved ${m.path}`, 4000); markChanged(m.changed); break;
      case "save_refused": onSaveRefused(m); break;
      case "fit_started": $("fit-section").hidden = false; $("fit-info").textContent = "fitting…"; break;
      case "fit": onFit(m); break;
      case "error": probe.errors += 1; showError("server: " + m.error); break;
      default: break;
    }
  }

  // -- geometry helpers ---------------------------------------------------------------------------
  const pt = (p) => `${p[0]},${-p[1]}`;
  function el(name, attrs, parent) {
    const e = document.createElementNS(NS, name);
    for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (parent) parent.appendChild(e);
    return e;
  }
  function world(body, pose) {
    const c = Math.cos(pose[2]), s = Math.sin(pose[2]);
    return body.map((q) => [pose[0] + c * q[0] - s * q[1], pose[1] + s * q[0] + c * q[1]]);
  }
  function colour(bodyName, k) {
    const b = S.bodies[bodyName];
    return b && b.colour >= 0 ? COLOURS[b.colour % COLOURS.length][k] : "#555";
  }
  function poly(points, attrs, parent) {
    return el("polygon", Object.assign({points: points.map(pt).join(" "), "vector-effect": "non-scaling-stroke"}, attrs),
              parent);
  }
  function line(points, attrs, parent) {
    return el("polyline", Object.assign({points: points.map(pt).join(" "), fill: "none",
                                         "vector-effect": "non-scaling-stroke"}, attrs), parent);
  }
  function pxPerM() { return svg.clientWidth / view.w; }
  function fontSize(px) { return px / pxPerM(); }
  function text(p, s, px, attrs, parent) {
    const t = el("text", Object.assign({x: p[0], y: -p[1], "font-size": fontSize(px), "paint-order": "stroke",
                                        stroke: "white", "stroke-width": fontSize(3)}, attrs), parent);
    t.textContent = s;
    return t;
  }

  // -- the static scene ---------------------------------------------------------------------------
  const layers = {};
  function setupStatic() {
    $("scene-title").textContent = S.title;
    $("file-name").textContent = S.file;
    document.title = `crashsim live: ${S.file}`;
    svg.innerHTML = "";
    for (const name of ["underlay", "zones", "map", "obstacles", "evidence", "band", "tracks", "approach", "paths",
                        "impactpose", "rest", "now", "impacts", "handles", "labels"]) {
      layers[name] = el("g", {id: "layer-" + name}, svg);
    }
    controls = {};
    values = {};
    for (const c of S.controls) { controls[c.path] = c; values[c.path] = c.written; }
    buildControls();
    view = null;
    $("band-section").hidden = !S.uncertainty;
    $("fit").disabled = !S.fit;
  }

  function drawStatic() {
    for (const k of ["underlay", "zones", "map", "obstacles", "evidence"]) layers[k].innerHTML = "";
    if (S.underlay) {
      const m = S.underlay.matrix;
      // pixel (col, row) -> scene: [m00 m01 m02; m10 m11 m12]; the page's y is -y
      el("image", {href: `underlay.png?token=${encodeURIComponent(token)}`, width: S.underlay.width,
                   height: S.underlay.height, opacity: S.underlay.opacity, preserveAspectRatio: "none",
                   transform: `matrix(${m[0][0]},${-m[1][0]},${m[0][1]},${-m[1][1]},${m[0][2]},${-m[1][2]})`},
         layers.underlay);
    }
    S.zones.forEach((z, i) => {
      poly(z.polygon, {fill: ["#e9f3d9", "#f6ecd5", "#e2ecf6", "#f3e0e6"][i % 4], stroke: "#8a9a6a",
                       "stroke-width": 0.8, class: "zone"}, layers.zones);
    });
    for (const m of S.map_lines) {
      line(m.points, {stroke: m.colour || "#777", "stroke-width": m.style === "edge" ? 1.6 : 1.0,
                      "stroke-dasharray": /centre|lane/.test(m.style) ? "8 6" : null}, layers.map);
    }
    for (const o of S.obstacles) for (const p of o.pieces) poly(p, {fill: "#c8c8c8", stroke: "#444", "stroke-width": 0.8},
                                                                layers.obstacles);
    const ev = S.evidence;
    ev.rest.forEach((r) => {
      const b = S.bodies[r.body];
      if (b && b.outline && r.heading !== null) {
        poly(world(b.outline, [r.position[0], r.position[1], r.heading]),
             {fill: "none", stroke: EVIDENCE, "stroke-width": 1.2, "stroke-dasharray": "5 3", class: "ev-rest"},
             layers.evidence);
      }
      el("circle", {cx: r.position[0], cy: -r.position[1], r: r.tolerance, fill: "none", stroke: EVIDENCE,
                    "stroke-width": 0.7, "stroke-dasharray": "2 2", "vector-effect": "non-scaling-stroke"},
         layers.evidence);
    });
    for (const m of ev.marks) line(m.points, {stroke: EVIDENCE, "stroke-width": 2.2, "stroke-opacity": 0.75,
                                              class: "ev-mark"}, layers.evidence);
    if (ev.impact_point) {
      const p = ev.impact_point.position;
      el("circle", {cx: p[0], cy: -p[1], r: ev.impact_point.tolerance, fill: "none", stroke: EVIDENCE,
                    "stroke-width": 0.7, "stroke-dasharray": "2 2", "vector-effect": "non-scaling-stroke"},
         layers.evidence);
      text(p, "★", 16, {fill: EVIDENCE, "text-anchor": "middle", "dominant-baseline": "central", stroke: "none"},
           layers.evidence);
    }
  }

  function extent() {
    let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    const add = (p) => { lo = [Math.min(lo[0], p[0]), Math.min(lo[1], p[1])]; hi = [Math.max(hi[0], p[0]), Math.max(hi[1], p[1])]; };
    for (const b in R.poses) {
      const ps = R.poses[b], body = S.bodies[b];
      for (const p of ps) add(p);
      if (body && body.outline) for (const q of [ps[0], ps[ps.length - 1]]) world(body.outline, q).forEach(add);
    }
    for (const r of S.evidence.rest) add(r.position);
    for (const m of S.evidence.marks) m.points.forEach(add);
    for (const b in R.approach) R.approach[b].forEach(add);
    const pad = 6, w = hi[0] - lo[0] + 2 * pad, h = hi[1] - lo[1] + 2 * pad;
    const aspect = svg.clientHeight / Math.max(svg.clientWidth, 1);
    const W = Math.max(w, h / aspect), H = W * aspect;
    return {x: (lo[0] + hi[0]) / 2 - W / 2, y: (lo[1] + hi[1]) / 2 - H / 2, w: W, h: H};
  }
  function applyView() {
    svg.setAttribute("viewBox", `${view.x} ${-(view.y + view.h)} ${view.w} ${view.h}`);
    // a scale bar of a round length in the file's unit, about 120 px long
    const pxPerUnit = svg.clientWidth / view.w / S.per_m;
    const raw = 120 / pxPerUnit, p = Math.pow(10, Math.floor(Math.log10(raw)));
    const len = [1, 2, 5, 10].map((k) => k * p).filter((x) => x <= raw * 1.5).pop() || p;
    $("scalebar-bar").style.width = `${len * pxPerUnit}px`;
    $("scalebar-text").textContent = `${Number(len.toPrecision(3))} ${S.length_unit}`;
  }

  // -- a result -----------------------------------------------------------------------------------
  function onResult(m) {
    probe.results += 1;
    probe.lastAnswered = Math.max(probe.lastAnswered, m.seq);
    probe.messages.push(["result", m.seq]);
    answered(m.seq);
    if (m.seq < lastShown) return;  // an older answer after a newer one: never shown
    R = m;
    lastShown = m.seq;
    if ((m.seq === lastSent && !dirty) || m.seq <= 0) {
      values = Object.assign({}, m.values);
      status("up to date", "");
    }
    hideError();
    if (!view) { view = extent(); applyView(); drawStatic(); }
    drawResult();
    updatePanel();
    markChanged(m.changed);
    if (band) layers.band.setAttribute("opacity", "0.35");  // the band of an older state until its own comes
    const s = m.seq;
    const n = upTo[s];
    requestAnimationFrame(() => { if (n !== undefined) probe.drawnT[n] = performance.now(); probe.lastDrawn = s; });
  }

  function onInvalid(m) {
    probe.invalid += 1;
    if (m.seq !== undefined) probe.lastAnswered = Math.max(probe.lastAnswered, m.seq);
    answered(m.seq);
    if ((m.seq !== undefined && m.seq < lastSent) || dirty) return;  // a newer change is on its way
    values = Object.assign({}, m.values || values);  // the last good values
    showError(m.error);
    status("invalid input: last good result shown", "bad");
    syncControls();
  }

  function drawResult() {
    for (const k of ["tracks", "approach", "paths", "impactpose", "rest", "impacts", "handles", "labels"]) {
      layers[k].innerHTML = "";
    }
    for (const tr of R.tracks) {
      line(tr.points, {stroke: colour(tr.body, 0), "stroke-width": 0.6, "stroke-opacity": 0.55, class: "track"},
           layers.tracks);
      for (const [a, b] of tr.sliding) {
        line(tr.points.slice(a, b), {stroke: "#222", "stroke-width": 2.0, "stroke-opacity": 0.7, class: "skid"},
             layers.tracks);
      }
    }
    for (const b in R.approach) {
      line(R.approach[b], {stroke: colour(b, 0), "stroke-width": 1.0, "stroke-dasharray": "7 3 2 3"}, layers.approach);
    }
    for (const b in R.poses) {
      const ps = R.poses[b];
      if (ps.length > 1) line(ps, {stroke: colour(b, 0), "stroke-width": 1.4, class: "path", "data-body": b},
                              layers.paths);
      const body = S.bodies[b];
      if (!body || !body.outline) continue;
      const g = el("g", {class: "vehicle-impact", "data-vehicle": body.vehicle}, layers.impactpose);
      poly(world(body.outline, ps[0]), {fill: colour(b, 1), "fill-opacity": 0.75, stroke: colour(b, 0),
                                        "stroke-width": 1.4}, g);
      for (const a of body.axles) line(world([[a[0], -a[1] / 2], [a[0], a[1] / 2]], ps[0]),
                                       {stroke: colour(b, 0), "stroke-width": 1.0}, g);
      if (ps.length > 1) {
        poly(world(body.outline, ps[ps.length - 1]), {fill: "none", stroke: colour(b, 0), "stroke-width": 1.6,
                                                      class: "rest-outline"}, layers.rest);
        text(ps[ps.length - 1], b, 10, {"text-anchor": "middle", "dominant-baseline": "central"}, layers.labels);
      }
    }
    for (const v of S.vehicles) {
      for (const h of v.hitches) {
        const p = world([h.point], R.poses[h.front][0])[0];
        el("circle", {cx: p[0], cy: -p[1], r: fontSize(3), fill: "white", stroke: "#222",
                      "vector-effect": "non-scaling-stroke"}, layers.impactpose);
      }
    }
    for (const i of R.impacts) {
      el("circle", {cx: i.point[0], cy: -i.point[1], r: fontSize(7), fill: "#fff", stroke: "#b00020",
                    "stroke-width": 1.2, "vector-effect": "non-scaling-stroke"}, layers.impacts);
      text(i.point, String(i.event), 9, {"text-anchor": "middle", "dominant-baseline": "central", fill: "#b00020",
                                        stroke: "none", class: "impact-number"}, layers.impacts);
    }
    drawHandles();
    drawNow();
  }

  // the bodies at the slider's time
  function drawNow() {
    layers.now.innerHTML = "";
    if (!R) return;
    const n = R.times.length;
    const i = Math.min(tIndex, n - 1);
    $("time").max = String(Math.max(n - 1, 1));
    $("time").value = String(i);
    $("time-label").textContent = `t = ${(R.times[i] || 0).toFixed(2)} s of ${R.t_end.toFixed(2)} s`;
    if (i === 0) return;
    for (const b in R.poses) {
      const body = S.bodies[b];
      const ps = R.poses[b];
      if (!body || !body.outline || ps.length < 2) continue;
      poly(world(body.outline, ps[Math.min(i, ps.length - 1)]), {fill: colour(b, 1), "fill-opacity": 0.5,
                                                                 stroke: colour(b, 0), "stroke-width": 1.2}, layers.now);
    }
  }

  // -- handles: the vehicles at impact, their headings, the point of impact and the normal ----------
  function firstBody(v) { return v.bodies[0]; }
  function handleCircle(p, cls, title) {
    const c = el("circle", {cx: p[0], cy: -p[1], r: fontSize(6), class: "handle " + cls, fill: "#fff",
                            stroke: "#222", "stroke-width": 1.5, "vector-effect": "non-scaling-stroke"}, layers.handles);
    el("title", {}, c).textContent = title;
    return c;
  }
  function drawHandles() {
    for (const v of S.vehicles) {
      if (v.barrier || !controls[`vehicles.${v.name}.heading`]) continue;
      const b = firstBody(v), pose = R.poses[b][0], body = S.bodies[b];
      const reach = body.outline ? Math.max(...body.outline.map((q) => q[0])) + 1.5 : 3;
      const h = [pose[0] + reach * Math.cos(pose[2]), pose[1] + reach * Math.sin(pose[2])];
      line([[pose[0], pose[1]], h], {stroke: "#222", "stroke-width": 0.8, "stroke-dasharray": "3 2"}, layers.handles);
      handleCircle(h, "rot heading", `turn ${v.name}'s heading`).dataset.vehicle = v.name;
    }
    const p = impactPoint();
    if (p) {
      handleCircle(p, "point", "move the point of impact");
      const a = normalAngle();
      if (a !== null) {
        const q = [p[0] + 3 * Math.cos(a), p[1] + 3 * Math.sin(a)];
        line([p, q], {stroke: "#b00020", "stroke-width": 1.4}, layers.handles);
        handleCircle(q, "rot normal", "turn the crush normal");
      }
    }
  }
  function num(path) { const c = controls[path]; return c ? parseFloat(values[path]) / c.per_si : null; }
  function impactPoint() {
    if (!controls["impact.point[0]"]) return null;
    const f = R.frames.point, x = num("impact.point[0]"), y = num("impact.point[1]");
    const c = Math.cos(f[2]), s = Math.sin(f[2]);
    return [f[0] + c * x - s * y, f[1] + s * x + c * y];
  }
  function normalAngle() {
    return controls["impact.normal"] ? num("impact.normal") + R.frames.normal[2] : null;
  }
  function write(path, si) {
    const c = controls[path];
    const x = si * c.per_si;
    const digits = c.kind === "angle" ? 3 : 4;
    const text = Number(x.toFixed(digits)).toString();
    values[path] = c.unit ? `${text} ${c.unit}` : Number(text);
  }

  let drag = null;
  function worldOf(ev) {
    const r = svg.getBoundingClientRect();
    return [view.x + (ev.clientX - r.left) / r.width * view.w, view.y + view.h - (ev.clientY - r.top) / r.height * view.h];
  }
  svg.addEventListener("pointerdown", (ev) => {
    if (!R || !view) return;
    const target = ev.target;
    const p = worldOf(ev);
    const group = target.closest ? target.closest(".vehicle-impact") : null;
    pushUndo();
    if (target.classList.contains("heading")) {
      const v = S.vehicles.find((x) => x.name === target.dataset.vehicle);
      drag = {kind: "heading", v: v, cg: R.poses[firstBody(v)][0], h0: num(`vehicles.${v.name}.heading`)};
    } else if (target.classList.contains("point")) {
      drag = {kind: "point"};
    } else if (target.classList.contains("normal")) {
      drag = {kind: "normal", p: impactPoint(), n0: num("impact.normal")};
    } else if (group && controls[`vehicles.${group.dataset.vehicle}.position[0]`]) {
      const v = group.dataset.vehicle;
      drag = {kind: "vehicle", v: v, p0: p, x0: num(`vehicles.${v}.position[0]`), y0: num(`vehicles.${v}.position[1]`)};
    } else {
      undo.pop();
      drag = {kind: "pan", p0: [ev.clientX, ev.clientY], view0: Object.assign({}, view)};
      svg.classList.add("panning");
    }
    svg.setPointerCapture(ev.pointerId);
    ev.preventDefault();
  });
  svg.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const p = worldOf(ev);
    if (drag.kind === "pan") {
      const r = svg.getBoundingClientRect();
      view.x = drag.view0.x - (ev.clientX - drag.p0[0]) / r.width * view.w;
      view.y = drag.view0.y + (ev.clientY - drag.p0[1]) / r.height * view.h;
      applyView();
      return;
    }
    if (drag.kind === "vehicle") {
      write(`vehicles.${drag.v}.position[0]`, drag.x0 + p[0] - drag.p0[0]);
      write(`vehicles.${drag.v}.position[1]`, drag.y0 + p[1] - drag.p0[1]);
    } else if (drag.kind === "heading") {
      let a = Math.atan2(p[1] - drag.cg[1], p[0] - drag.cg[0]);
      while (a - drag.h0 > Math.PI) a -= 2 * Math.PI;
      while (a - drag.h0 < -Math.PI) a += 2 * Math.PI;
      write(`vehicles.${drag.v.name}.heading`, a);
    } else if (drag.kind === "point") {
      const f = R.frames.point, c = Math.cos(f[2]), s = Math.sin(f[2]);
      const d = [p[0] - f[0], p[1] - f[1]];
      write("impact.point[0]", c * d[0] + s * d[1]);
      write("impact.point[1]", -s * d[0] + c * d[1]);
    } else if (drag.kind === "normal") {
      let a = Math.atan2(p[1] - drag.p[1], p[0] - drag.p[0]) - R.frames.normal[2];
      while (a - drag.n0 > Math.PI) a -= 2 * Math.PI;
      while (a - drag.n0 < -Math.PI) a += 2 * Math.PI;
      write("impact.normal", a);
    }
    syncControls();
    sendValues(ev.timeStamp);
  });
  function endDrag() { drag = null; svg.classList.remove("panning"); updateUndoButtons(); }
  svg.addEventListener("pointerup", endDrag);
  svg.addEventListener("pointercancel", endDrag);
  svg.addEventListener("wheel", (ev) => {
    if (!view) return;
    ev.preventDefault();
    const p = worldOf(ev), k = Math.exp(ev.deltaY * 0.0015);
    view = {x: p[0] - (p[0] - view.x) * k, y: p[1] - (p[1] - view.y) * k, w: view.w * k, h: view.h * k};
    applyView();
    drawStatic();
    if (R) drawResult();
    if (band) drawBand();
  }, {passive: false});

  // -- the panel ------------------------------------------------------------------------------------
  const rows = {};
  function buildControls() {
    const box = $("controls");
    box.innerHTML = "";
    const groups = {};
    for (const c of S.controls) {
      if (!groups[c.group]) {
        const g = document.createElement("div");
        g.className = "group";
        g.innerHTML = `<h3></h3>`;
        g.querySelector("h3").textContent = c.group;
        box.appendChild(g);
        groups[c.group] = g;
      }
      const row = document.createElement("div");
      row.className = "ctl";
      row.dataset.path = c.path;
      const label = document.createElement("label");
      label.textContent = c.label;
      label.title = c.path;
      const input = document.createElement("input");
      input.type = "text";
      input.name = c.path;
      input.title = `${c.path}: a number with its unit, as in the file (e.g. ${JSON.stringify(c.written)})`;
      const slider = document.createElement("input");
      slider.type = "range";
      slider.min = String(c.lower);
      slider.max = String(c.upper);
      slider.step = String(c.step);
      slider.setAttribute("aria-label", c.label);
      input.addEventListener("focus", pushUndo);
      input.addEventListener("input", () => { input.dataset.editing = "1"; });
      input.addEventListener("change", (ev) => {
        delete input.dataset.editing;
        const t = input.value.trim();
        values[c.path] = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(t) && !c.unit ? Number(t) : t;
        sendValues(ev.timeStamp);
        updateUndoButtons();
      });
      slider.addEventListener("pointerdown", pushUndo);
      slider.addEventListener("keydown", pushUndo);
      slider.addEventListener("input", (ev) => {
        values[c.path] = c.unit ? `${slider.value} ${c.unit}` : Number(slider.value);
        input.value = String(values[c.path]);
        sendValues(ev.timeStamp);
      });
      slider.addEventListener("change", updateUndoButtons);
      row.append(label, input, slider);
      groups[c.group].appendChild(row);
      rows[c.path] = {row, input, slider};
    }
    syncControls();
  }
  function syncControls() {
    for (const p in rows) {
      const r = rows[p], v = values[p];
      if (!r.input.dataset.editing) r.input.value = String(v);
      r.input.classList.remove("bad");
      const x = parseFloat(v);
      if (isFinite(x) && document.activeElement !== r.slider) r.slider.value = String(x);
    }
  }
  function markChanged(changed) {
    for (const p in rows) rows[p].row.classList.toggle("changed", !!(changed && p in changed));
  }
  function cell(tr, text, cls) { const td = document.createElement("td"); td.textContent = text; if (cls) td.className = cls; tr.appendChild(td); return td; }
  function updatePanel() {
    syncControls();
    const ev = $("evidence");
    ev.innerHTML = "";
    for (const c of R.evidence) {
      const tr = document.createElement("tr");
      cell(tr, c.passed ? "PASS" : "FAIL", c.passed ? "pass" : "fail");
      cell(tr, `${c.kind}: ${c.name}`);
      cell(tr, c.residual, "num residual");
      cell(tr, `tol ${c.tolerance}`, "num");
      ev.appendChild(tr);
    }
    $("evidence-count").textContent = `${R.n_passed} of ${R.n_checks} within tolerance`;
    const bt = $("bodies");
    bt.innerHTML = "<tr><th>body</th><th>delta-v</th><th>PDOF</th><th>speed after</th></tr>";
    for (const b of R.bodies) {
      const tr = document.createElement("tr");
      cell(tr, b.name); cell(tr, b.delta_v, "num delta-v"); cell(tr, b.pdof, "num"); cell(tr, b.speed_after, "num");
      bt.appendChild(tr);
    }
    const rt = $("rest");
    rt.innerHTML = "";
    for (const b in R.rest) { const tr = document.createElement("tr"); cell(tr, b); cell(tr, R.rest[b].text, "num"); rt.appendChild(tr); }
    const et = $("energy");
    et.innerHTML = "";
    for (const [k, v] of R.energy) { const tr = document.createElement("tr"); cell(tr, k); cell(tr, v, "num"); et.appendChild(tr); }
    const wl = $("warnings");
    wl.innerHTML = "";
    for (const w of R.warnings) { const li = document.createElement("li"); li.textContent = w; wl.appendChild(li); }
    if (!R.warnings.length) wl.innerHTML = "<li style='color:#555'>none</li>";
    const leg = $("legend");
    leg.innerHTML = "";
    for (const v of S.vehicles) {
      if (v.barrier) continue;
      const d = document.createElement("div");
      d.innerHTML = `<span style="color:${COLOURS[v.colour % COLOURS.length][0]}">■</span> `;
      d.append(`${v.name}${v.description ? ": " + v.description : ""}`);
      leg.appendChild(d);
    }
    S.zones.forEach((z, i) => {
      const d = document.createElement("div");
      const f = values[`runout.zones[${i}].friction`];
      d.innerHTML = `<span style="color:#8a9a6a">▦</span> `;
      d.append(`zone ${z.name}: f = ${f === undefined ? z.friction : f}`);
      leg.appendChild(d);
    });
    if (S.zones.length && values["runout.road_friction"] !== undefined) {
      const d = document.createElement("div");
      d.append(`road outside the zones: f = ${values["runout.road_friction"]}`);
      leg.appendChild(d);
    }
    const d = document.createElement("div");
    d.innerHTML = `<span style="color:${EVIDENCE}">- - ★</span> evidence; ● impacts by number; bold: sliding tyres`;
    leg.appendChild(d);
  }

  // -- the band ---------------------------------------------------------------------------------------
  function onBand(m) {
    probe.bands += 1;
    probe.lastBand = {generation: m.generation, seconds: m.seconds, n: m.n, meets: m.n_meets_all};
    if (!R || m.generation !== R.generation) return;
    band = m;
    drawBand();
    $("band-info").textContent = `${m.share_text} (${m.n_failed} failed; ${m.seconds.toFixed(2)} s, ` +
      `samples as crashsim mc draws them, about the values set here)`;
  }
  function drawBand() {
    layers.band.innerHTML = "";
    layers.band.setAttribute("opacity", "1");
    if (!band || !$("show-band").checked) return;
    for (const s of band.samples) {
      for (const b in s.paths) line(s.paths[b], {stroke: colour(b, 0), "stroke-width": 0.6, "stroke-opacity": 0.25},
                                    layers.band);
      for (const b in s.rest) {
        const body = S.bodies[b];
        if (body && body.outline) poly(world(body.outline, s.rest[b]), {fill: "none", stroke: colour(b, 0),
                                                                        "stroke-width": 0.5, "stroke-opacity": 0.35,
                                                                        class: "band-rest"}, layers.band);
      }
    }
  }
  $("show-band").addEventListener("change", drawBand);

  // -- undo, save, reload, fit, export ---------------------------------------------------------------
  function snapshot() { return JSON.stringify(values); }
  function pushUndo() {
    const s = snapshot();
    if (!undo.length || undo[undo.length - 1] !== s) { undo.push(s); redo.length = 0; }
    updateUndoButtons();
  }
  function updateUndoButtons() {
    $("undo").disabled = !undo.length || (undo.length === 1 && undo[0] === snapshot());
    $("redo").disabled = !redo.length;
  }
  function restore(s) { values = JSON.parse(s); syncControls(); sendValues(); updateUndoButtons(); }
  function doUndo() {
    while (undo.length && undo[undo.length - 1] === snapshot()) undo.pop();
    if (!undo.length) return;
    redo.push(snapshot());
    restore(undo.pop());
  }
  function doRedo() { if (!redo.length) return; undo.push(snapshot()); restore(redo.pop()); }
  $("undo").onclick = doUndo;
  $("redo").onclick = doRedo;
  document.addEventListener("keydown", (ev) => {
    if ((ev.ctrlKey || ev.metaKey) && ev.key === "z") { ev.preventDefault(); doUndo(); }
    if ((ev.ctrlKey || ev.metaKey) && ev.key === "y") { ev.preventDefault(); doRedo(); }
  });
  $("save").onclick = () => send({type: "save"});
  $("save-as").onclick = () => {
    const name = window.prompt("Save as a new file in the scene's folder:", S.file.replace(/\.toml$/, "-live.toml"));
    if (name) send({type: "save_as", name: name});
  };
  $("reload").onclick = () => { send({type: "reload"}); };
  $("fit").onclick = () => send({type: "fit"});
  $("export").onchange = () => {
    const f = $("export").value;
    $("export").value = "";
    if (f) window.open(`export?format=${f}&token=${encodeURIComponent(token)}`, "_blank");
  };
  function onSaveRefused(m) {
    const b = $("banner");
    b.hidden = false;
    b.textContent = m.error;
    if (m.changed_on_disk) {
      const r = document.createElement("button"); r.textContent = "Reload"; r.onclick = () => { b.hidden = true; send({type: "reload"}); };
      const s = document.createElement("button"); s.textContent = "Save as…"; s.onclick = () => { b.hidden = true; $("save-as").click(); };
      b.append(r, s);
    }
    const c = document.createElement("button"); c.textContent = "Close"; c.onclick = () => { b.hidden = true; };
    b.append(c);
  }
  function onFit(m) {
    $("fit-section").hidden = false;
    const box = $("fit-info");
    if (!m.ok) { box.textContent = m.error; return; }
    box.innerHTML = "";
    const p = document.createElement("p");
    p.textContent = `${m.success ? "converged" : "did not converge"}; ${m.n_agree} of ${m.starts} starts agree`;
    box.appendChild(p);
    const t = document.createElement("table");
    for (const u of m.unknowns) {
      const tr = document.createElement("tr");
      cell(tr, u.path); cell(tr, u.value, "num"); cell(tr, `[${u.interval[0]}, ${u.interval[1]}]`, "num");
      t.appendChild(tr);
    }
    box.appendChild(t);
    const apply = document.createElement("button");
    apply.textContent = "Use these values";
    apply.onclick = () => { pushUndo(); for (const u of m.unknowns) if (controls[u.path]) write(u.path, u.si); syncControls(); sendValues(); };
    box.appendChild(apply);
  }
  function banner(textValue, ms) {
    const b = $("banner"); b.hidden = false; b.textContent = textValue;
    if (ms) setTimeout(() => { b.hidden = true; }, ms);
  }
  function showError(e) { const x = $("error"); x.hidden = false; x.textContent = e; }
  function hideError() { $("error").hidden = true; }

  // -- time ------------------------------------------------------------------------------------------
  $("time").addEventListener("input", () => { tIndex = parseInt($("time").value, 10); drawNow(); });
  $("play").onclick = () => {
    playing = !playing;
    $("play").textContent = playing ? "❚❚" : "▶";
    let last = performance.now();
    const step = (now) => {
      if (!playing || !R) return;
      const dt = R.times.length > 1 ? R.times[1] - R.times[0] : 0.01;
      const k = Math.floor((now - last) / 1000 / dt);
      if (k > 0) { tIndex += k; last = now; }
      if (tIndex >= R.times.length - 1) { tIndex = R.times.length - 1; playing = false; $("play").textContent = "▶"; }
      drawNow();
      if (playing) requestAnimationFrame(step);
    };
    if (tIndex >= (R ? R.times.length - 1 : 0)) tIndex = 0;
    requestAnimationFrame(step);
  };
  window.addEventListener("resize", () => { if (view && R) { view = extent(); applyView(); drawStatic(); drawResult(); } });
  connect();
})();
