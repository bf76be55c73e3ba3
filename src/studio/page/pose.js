// Posing with the mouse. Two tools (and the depth and stiffness brushes of paint.js):
// - Drag (D): a click on a vertex pins it and drags it (a frame between keyframes, when one is
//   shown, becomes a keyframe with that pin: the click acts on what is shown); dragging a pin
//   moves it, and every selected pin with it; Shift+click on a vertex pins it without dragging.
// - Pins (P): a click on a vertex pins it, dragging a pin places it on another vertex; the mesh
//   does not move.
// With either: Shift+click on a pin selects it (or not); a drag that starts off the mesh (or
// Ctrl+drag) selects the pins in a box; two or more selected pins show a frame with a handle
// to rotate them (the round one above) and one to scale them (the square corner) about their
// centre. Unselected pins hold still. A right-click removes a pin. Wheel zooms about the
// cursor, the middle button or Alt+drag pans. The vertex and triangle under the cursor can be
// highlighted (the original editor's aid). A click picks a vertex of the part drawn in front
// under the cursor (a hand over the torso pins the hand). The joints tool is parts.js's.

import { S, $, canvas, ctx, dpr, eventCanvas, toCanvas, toWorld, withinReach, zoomAt, redraw } from "./view.js";
import { send, request } from "./net.js";

// The triangle drawn in front under a canvas point (the higher depth level, then the later
// triangle, as the mesh is drawn), among those of parts shown and not locked; or -1.
function frontFaceAt(px, py) {
  const [x, y] = toWorld(px, py), P = S.pose, F = S.faces;
  let best = -1, bestDepth = -Infinity;
  for (let f = 0; f < S.m; f++) {
    if (S.faceHidden && S.faceHidden[f]) continue;
    const a = 2 * F[3 * f], b = 2 * F[3 * f + 1], c = 2 * F[3 * f + 2];
    const d1 = (x - P[b]) * (P[a + 1] - P[b + 1]) - (P[a] - P[b]) * (y - P[b + 1]);
    const d2 = (x - P[c]) * (P[b + 1] - P[c + 1]) - (P[b] - P[c]) * (y - P[c + 1]);
    const d3 = (x - P[a]) * (P[c + 1] - P[a + 1]) - (P[c] - P[a]) * (y - P[a + 1]);
    const neg = d1 < 0 || d2 < 0 || d3 < 0, pos = d1 > 0 || d2 > 0 || d3 > 0;
    if (neg && pos) continue;
    if (S.vertexLocked && S.vertexLocked[F[3 * f]]) continue;
    const depth = S.depth ? S.depth[f] : 0;
    if (depth >= bestDepth) { best = f; bestDepth = depth; }
  }
  return best;
}

// The vertices a click at a canvas point may pick: those of the part drawn in front there (a
// hand over the torso picks the hand), or every vertex off the parts.
function pickable(px, py) {
  const parts = S.state && S.state.parts;
  if (!parts || !S.pose) return [0, S.n];
  const f = frontFaceAt(px, py);
  const p = f < 0 ? null : parts.find((q) => f >= q.faces[0] && f < q.faces[1]);
  return p ? [p.vertices[0], Math.min(p.vertices[1], S.n)] : [0, S.n];
}

function nearestVertex(px, py, radius) {
  let best = -1, bestD = radius * radius;
  const [from, to] = pickable(px, py);
  for (let v = from; v < to; v++) {
    // A locked part's vertices take no new pin.
    if (S.vertexLocked && S.vertexLocked[v]) continue;
    const [x, y] = toCanvas(S.pose[2 * v], S.pose[2 * v + 1]);
    const d = (x - px) ** 2 + (y - py) ** 2;
    if (d < bestD) { bestD = d; best = v; }
  }
  return best;
}

function nearestPin(px, py, radius) {
  let best = -1, bestD = radius * radius;
  S.pins.forEach((v, i) => {
    const [x, y] = toCanvas(S.pose[2 * v], S.pose[2 * v + 1]);
    const d = (x - px) ** 2 + (y - py) ** 2;
    if (d < bestD) { bestD = d; best = i; }
  });
  return best;
}

// The triangle under a canvas point, or -1.
function faceAt(px, py) {
  const [x, y] = toWorld(px, py), P = S.pose, F = S.faces;
  for (let f = 0; f < S.m; f++) {
    const a = 2 * F[3 * f], b = 2 * F[3 * f + 1], c = 2 * F[3 * f + 2];
    const d1 = (x - P[b]) * (P[a + 1] - P[b + 1]) - (P[a] - P[b]) * (y - P[b + 1]);
    const d2 = (x - P[c]) * (P[b + 1] - P[c + 1]) - (P[b] - P[c]) * (y - P[c + 1]);
    const d3 = (x - P[a]) * (P[c + 1] - P[a + 1]) - (P[c] - P[a]) * (y - P[a + 1]);
    const neg = d1 < 0 || d2 < 0 || d3 < 0, pos = d1 > 0 || d2 > 0 || d3 > 0;
    if (!(neg && pos)) return f;
  }
  return -1;
}

const posing = () => S.state && S.state.mode === "pose";
const pinPoint = (v) => [S.pose[2 * v], S.pose[2 * v + 1]];

// The selected pins that are pins of the keyframe shown (the others are forgotten).
function selection() {
  if (S.showing !== "pose") return [];
  for (const v of [...S.selected]) if (!S.pins.includes(v)) S.selected.delete(v);
  return [...S.selected];
}

// The frame around two or more selected pins (canvas pixels), with its handles.
function selectionFrame() {
  const sel = selection();
  if (sel.length < 2 || !S.pose) return null;
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (const v of sel) {
    const [x, y] = S.drag || S.xform ? toCanvas(...dragTarget(v)) : toCanvas(...pinPoint(v));
    x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y);
  }
  const pad = 14 * dpr();
  x0 -= pad; y0 -= pad; x1 += pad; y1 += pad;
  return { x0, y0, x1, y1, rotate: [(x0 + x1) / 2, y0 - 22 * dpr()], scale: [x1, y1] };
}

function dragTarget(v) {
  const d = S.drag;
  const i = d ? d.pins.indexOf(v) : -1;
  return i >= 0 ? d.targets[i] : pinPoint(v);
}

// Starts a drag of the keyframe's pins, with `moving` (vertex numbers) following the mouse.
function startDrag(moving, [px, py], kind = "move") {
  const pins = S.pins.slice();
  const base = pins.map((v) => pinPoint(v));
  const sel = moving.map((v) => pins.indexOf(v)).filter((i) => i >= 0);
  let centre = [0, 0];
  for (const i of sel) { centre[0] += base[i][0] / sel.length; centre[1] += base[i][1] / sel.length; }
  S.drag = { pins, base, targets: base.map((p) => p.slice()), moving: sel, kind, centre, from: toWorld(px, py) };
  redraw();
}

canvas.addEventListener("contextmenu", (e) => {
  e.preventDefault();
  if (!posing() || S.showing !== "pose" || S.tool === "joints") return;
  const [px, py] = eventCanvas(e);
  const i = nearestPin(px, py, 12 * dpr());
  if (i >= 0) send({ op: "pin_remove", vertex: S.pins[i] });
});

canvas.addEventListener("mousedown", (e) => {
  canvas.focus();
  const [px, py] = eventCanvas(e);
  if (e.button === 1 || (e.button === 0 && e.altKey)) {
    S.pan = { px, py, x: S.view.x, y: S.view.y };
    e.preventDefault();
    return;
  }
  if (!posing() || e.button !== 0 || !S.pose) return;
  // The brushes paint (paint.js).
  if (S.tool === "depth" || S.tool === "stiff" || S.tool === "joints") return;
  const shown = S.showing === "pose";
  // The selection's handles.
  const frame = shown ? selectionFrame() : null;
  if (frame && !e.shiftKey) {
    const near = (p) => Math.hypot(p[0] - px, p[1] - py) <= 9 * dpr();
    if (near(frame.rotate) || near(frame.scale)) {
      startDrag(selection(), [px, py], near(frame.rotate) ? "rotate" : "scale");
      return;
    }
  }
  const i = shown ? nearestPin(px, py, 12 * dpr()) : -1;
  if (i >= 0) {
    const v = S.pins[i];
    if (e.shiftKey) {
      if (S.selected.has(v)) S.selected.delete(v); else S.selected.add(v);
      redraw();
      return;
    }
    if (S.tool === "pins") { S.pinMove = { from: v, to: v, at: [px, py] }; redraw(); return; }
    const sel = selection();
    startDrag(sel.includes(v) && sel.length > 1 ? sel : [v], [px, py]);
    return;
  }
  const v = e.ctrlKey || e.metaKey ? -1 : nearestVertex(px, py, 14 * dpr());
  if (v < 0) {
    // Off the mesh (or Ctrl): a selection box.
    S.box = { x0: px, y0: py, x1: px, y1: py, add: e.shiftKey };
    redraw();
    return;
  }
  // On a frame between keyframes the server makes a keyframe of it with this one pin.
  const pins = shown ? [...S.pins, v] : [v];
  send({ op: "pin_add", vertex: v });
  S.pins = pins;
  S.showing = "pose";
  if (S.tool === "pins" || e.shiftKey) { redraw(); return; }
  S.selected.clear();
  startDrag([v], [px, py]);
});

window.addEventListener("mousemove", (e) => {
  const [px, py] = eventCanvas(e);
  if (S.pan) {
    S.view.x = S.pan.x + (px - S.pan.px);
    S.view.y = S.pan.y + (py - S.pan.py);
    redraw();
    return;
  }
  if (S.box) { S.box.x1 = px; S.box.y1 = py; redraw(); return; }
  if (S.pinMove) {
    const v = nearestVertex(px, py, 30 * dpr());
    if (v >= 0 && (v === S.pinMove.from || !S.pins.includes(v))) S.pinMove.to = v;
    S.pinMove.at = [px, py];
    redraw();
    return;
  }
  if (S.drag) {
    const d = S.drag, [wx, wy] = withinReach(toWorld(px, py));
    const c = d.centre;
    if (d.kind === "move" && d.moving.length === 1) {
      d.targets[d.moving[0]] = [wx, wy];
    } else if (d.kind === "move") {
      for (const i of d.moving) d.targets[i] = [d.base[i][0] + wx - d.from[0], d.base[i][1] + wy - d.from[1]];
    } else if (d.kind === "rotate") {
      const angle = Math.atan2(wy - c[1], wx - c[0]) - Math.atan2(d.from[1] - c[1], d.from[0] - c[0]);
      const cos = Math.cos(angle), sin = Math.sin(angle);
      for (const i of d.moving) {
        const x = d.base[i][0] - c[0], y = d.base[i][1] - c[1];
        d.targets[i] = [c[0] + cos * x - sin * y, c[1] + sin * x + cos * y];
      }
    } else {
      const k = Math.hypot(wx - c[0], wy - c[1]) / Math.max(Math.hypot(d.from[0] - c[0], d.from[1] - c[1]), 1e-12);
      for (const i of d.moving) d.targets[i] = [c[0] + k * (d.base[i][0] - c[0]), c[1] + k * (d.base[i][1] - c[1])];
    }
    d.targets = d.targets.map((t) => withinReach(t));
    // Only the pins moved here are ours: another tab may be dragging the others.
    request({ op: "drag", pins: d.pins, targets: d.targets.map((t) => t.slice()), moving: d.moving.map((i) => d.pins[i]) });
    return;
  }
  if ($("highlight").checked && e.target === canvas && S.pose && posing()) {
    const v = nearestVertex(px, py, 14 * dpr()), f = faceAt(px, py);
    if (!S.hover || S.hover.v !== v || S.hover.f !== f) { S.hover = { v, f }; redraw(); }
  } else if (S.hover) { S.hover = null; redraw(); }
});

window.addEventListener("mouseup", () => {
  if (S.pan) { S.pan = null; return; }
  if (S.box) {
    const b = S.box;
    S.box = null;
    const [x0, x1] = [Math.min(b.x0, b.x1), Math.max(b.x0, b.x1)], [y0, y1] = [Math.min(b.y0, b.y1), Math.max(b.y0, b.y1)];
    if (!b.add) S.selected.clear();
    if (S.showing === "pose") for (const v of S.pins) {
      const [x, y] = toCanvas(...pinPoint(v));
      if (x >= x0 && x <= x1 && y >= y0 && y <= y1) S.selected.add(v);
    }
    redraw();
    return;
  }
  if (S.pinMove) {
    const { from, to } = S.pinMove;
    S.pinMove = null;
    if (to !== from) {
      if (S.selected.delete(from)) S.selected.add(to);
      send({ op: "pin_move", from, to });
    }
    redraw();
    return;
  }
  if (!S.drag) return;
  S.drag = null;
  send({ op: "drag_end" });
  redraw();
});

canvas.addEventListener("mouseleave", () => { if (S.hover) { S.hover = null; redraw(); } });
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const [px, py] = eventCanvas(e);
  zoomAt(px, py, Math.exp(-e.deltaY * 0.0015));
}, { passive: false });

// Whether the pins are drawn: on a keyframe shown, when the pins the page holds are that
// keyframe's as the server last said (after a change in another tab, until its pins arrive,
// none rather than stale ones), and not while the playhead runs ahead of the shape shown
// (playing or scrubbing here). On a frame between keyframes no pin is drawn: pins belong to
// keyframes.
export function pinsShown() {
  if (S.showing !== "pose" || !S.pose || S.playing || S.sliding) return false;
  const st = S.state, k = S.frameInfo.keyframe;
  if (!st || k < 0 || !st.keyframes[k]) return true;
  return S.pinsKeyframe === k && st.keyframes[k].pins === S.pins.length;
}

// Drawn by the overlay: pins (selected ones ringed), the selection frame and its handles, the
// selection box, a pin being placed again, and the highlight under the cursor.
export function drawPins() {
  if (!pinsShown()) return;
  const sel = new Set(selection());
  for (const v of S.pins) {
    if (v >= S.n) continue;
    const [x, y] = toCanvas(...(S.drag ? dragTarget(v) : pinPoint(v)));
    const moving = S.pinMove && S.pinMove.from === v;
    ctx.fillStyle = moving ? "rgba(214,39,40,0.35)" : "#d62728";
    ctx.strokeStyle = "#fff";
    ctx.lineWidth = 2 * dpr();
    ctx.beginPath(); ctx.arc(x, y, 6 * dpr(), 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
    if (sel.has(v)) {
      ctx.strokeStyle = "#1f77b4";
      ctx.lineWidth = 2.5 * dpr();
      ctx.beginPath(); ctx.arc(x, y, 10 * dpr(), 0, 2 * Math.PI); ctx.stroke();
    }
  }
  if (S.pinMove && S.pinMove.to !== S.pinMove.from) {
    const [x, y] = toCanvas(...pinPoint(S.pinMove.to));
    ctx.setLineDash([4 * dpr(), 3 * dpr()]);
    ctx.strokeStyle = "#d62728";
    ctx.lineWidth = 2 * dpr();
    ctx.beginPath(); ctx.arc(x, y, 8 * dpr(), 0, 2 * Math.PI); ctx.stroke();
    ctx.setLineDash([]);
  }
  const frame = selectionFrame();
  if (frame) {
    ctx.strokeStyle = "#1f77b4";
    ctx.lineWidth = 1.5 * dpr();
    ctx.setLineDash([5 * dpr(), 4 * dpr()]);
    ctx.strokeRect(frame.x0, frame.y0, frame.x1 - frame.x0, frame.y1 - frame.y0);
    ctx.setLineDash([]);
    ctx.beginPath(); ctx.moveTo((frame.x0 + frame.x1) / 2, frame.y0); ctx.lineTo(...frame.rotate); ctx.stroke();
    ctx.fillStyle = "#fff";
    ctx.beginPath(); ctx.arc(...frame.rotate, 6 * dpr(), 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
    const h = 6 * dpr();
    ctx.fillRect(frame.scale[0] - h, frame.scale[1] - h, 2 * h, 2 * h);
    ctx.strokeRect(frame.scale[0] - h, frame.scale[1] - h, 2 * h, 2 * h);
  }
}

export function drawAids() {
  if (S.box) {
    const b = S.box;
    ctx.fillStyle = "rgba(31,119,180,0.12)";
    ctx.strokeStyle = "#1f77b4";
    ctx.lineWidth = 1 * dpr();
    ctx.fillRect(b.x0, b.y0, b.x1 - b.x0, b.y1 - b.y0);
    ctx.strokeRect(b.x0, b.y0, b.x1 - b.x0, b.y1 - b.y0);
  }
  if (S.hover && $("highlight").checked && S.pose) {
    const { v, f } = S.hover;
    ctx.lineWidth = 2 * dpr();
    if (f >= 0) {
      ctx.strokeStyle = "#ff7f0e";
      ctx.fillStyle = "rgba(255,127,14,0.25)";
      ctx.beginPath();
      for (let k = 0; k < 3; k++) {
        const [x, y] = toCanvas(...pinPoint(S.faces[3 * f + k]));
        if (k) ctx.lineTo(x, y); else ctx.moveTo(x, y);
      }
      ctx.closePath(); ctx.fill(); ctx.stroke();
    }
    if (v >= 0) {
      const [x, y] = toCanvas(...pinPoint(v));
      ctx.strokeStyle = "#ff7f0e";
      ctx.beginPath(); ctx.arc(x, y, 7 * dpr(), 0, 2 * Math.PI); ctx.stroke();
    }
  }
}

// The tools.
export function setTool(tool) {
  S.tool = tool;
  $("tool-drag").classList.toggle("on", tool === "drag");
  $("tool-pins").classList.toggle("on", tool === "pins");
  $("tool-depth").classList.toggle("on", tool === "depth");
  $("tool-stiff").classList.toggle("on", tool === "stiff");
  $("tool-joints").classList.toggle("on", tool === "joints");
  $("brush-tools").hidden = tool !== "depth" && tool !== "stiff";
  $("depth-level-label").hidden = tool !== "depth";
  canvas.classList.toggle("pins-tool", tool === "pins");
  canvas.classList.toggle("brush-tool", tool === "depth" || tool === "stiff");
  canvas.classList.toggle("joints-tool", tool === "joints");
  redraw();
}
$("tool-drag").onclick = () => setTool("drag");
$("tool-pins").onclick = () => setTool("pins");
$("tool-depth").onclick = () => setTool("depth");
$("tool-stiff").onclick = () => setTool("stiff");
$("tool-joints").onclick = () => setTool("joints");
export function selectAllPins() { if (S.showing === "pose") for (const v of S.pins) S.selected.add(v); redraw(); }
export function selectNone() { S.selected.clear(); redraw(); }
$("select-all-pins").onclick = selectAllPins;
$("select-none").onclick = selectNone;

// The pins panel.
export function drawPinPanel() {
  const sel = selection();
  const text = S.showing === "pose"
    ? `${S.pins.length} pins on this keyframe, ${sel.length} selected` + (sel.length >= 2 ? ": drag one to move them together, the round handle rotates them, the square scales them" : "")
    : "a frame between keyframes: a click on a vertex makes it a keyframe with that pin";
  if ($("pin-info").textContent !== text) $("pin-info").textContent = text;
}

// The method and its parameter.
export function syncMethod() {
  const st = S.state;
  if (!st) return;
  const method = $("method"), input = $("param"), label = $("param-label");
  if (document.activeElement !== method) method.value = st.method.name;
  const name = method.value;
  label.style.visibility = name === "arap" ? "hidden" : "visible";
  label.firstChild.textContent = name === "bounded" ? "K " : "weight ";
  if (document.activeElement !== input) input.value = name === "bounded" ? st.method.max_distortion : st.method.weight;
}
$("method").addEventListener("change", () => send({ op: "method", name: $("method").value }));
$("param").addEventListener("change", () => {
  const value = Number($("param").value);
  const name = $("method").value;
  send({ op: "method", name, ...(name === "bounded" ? { max_distortion: value } : { weight: value }) });
});
$("reset").onclick = () => send({ op: "reset" });
$("unpin").onclick = () => send({ op: "pins_clear" });
$("repair").onclick = () => send({ op: "repair" });
