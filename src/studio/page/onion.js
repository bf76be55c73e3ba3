// Onion skins: the keyframes before and after what is shown, drawn as tinted ghosts (earlier
// ones red, later ones green, fainter with distance) under the pins, while posing and
// scrubbing. Each ghost is the pose's outline (its boundary loops, stroked, as Grease Pencil
// draws its ghosts) built once per pose as a Path2D in the mesh's frame and drawn with the
// view's transform: a redraw costs one call per ghost, and its raster work grows with the
// outline, not with the triangles or the area (a filled silhouette cost about a tenth of the
// scrub rate with the canvas rasterised on the CPU).

import { S, $, ctx, dpr, redraw } from "./view.js";
import { needPoses } from "./net.js";
import { playheadTime } from "./timeline.js";

const BEFORE = [214, 39, 40], AFTER = [44, 160, 44];
const paths = new Map(); // keyframe -> { pos, fill, loops }: each ghost's outline path

// The keyframes ghosted now: up to `count` each side of the keyframe posed, or of the time shown.
export function ghostKeys() {
  const st = S.state;
  if (!st || !$("onion").checked || st.mode === "outline") return { before: [], after: [] };
  const count = Math.min(Math.max(1, Number($("onion-count").value) || 1), 4);
  const times = st.keyframes.map((k) => k.time);
  let below, above;
  if ("keyframe" in st.shown && !S.playing && !S.sliding) {
    below = st.current - 1;
    above = st.current + 1;
  } else {
    const t = playheadTime();
    above = times.findIndex((time) => time > t + 1e-9);
    if (above < 0) above = times.length;
    below = times.map((time) => time < t - 1e-9).lastIndexOf(true);
  }
  const before = [], after = [];
  for (let i = 0; i < count; i++) {
    if (below - i >= 0) before.push(below - i);
    if (above + i < times.length) after.push(above + i);
  }
  return { before, after };
}

// The boundary as closed loops (each boundary edge goes one way around its piece, so the
// loops are chained edge by edge), computed once per mesh.
let loops = null, loopsFor = null;
function boundaryLoops() {
  if (loopsFor === S.boundary) return loops;
  const next = new Map();
  for (const [a, b] of S.boundary) {
    if (!next.has(a)) next.set(a, []);
    next.get(a).push(b);
  }
  loops = [];
  for (const start of next.keys()) {
    while (next.get(start).length) {
      const loop = [start];
      let v = next.get(start).pop();
      while (v !== start && next.has(v) && next.get(v).length) {
        loop.push(v);
        v = next.get(v).pop();
      }
      loops.push(loop);
    }
  }
  loopsFor = S.boundary;
  return loops;
}

function pathsOf(k) {
  const ghost = S.ghosts.get(k);
  if (!ghost) return null;
  const cached = paths.get(k);
  if (cached && cached.pos === ghost.pos && cached.loops === boundaryLoops()) return cached;
  const P = ghost.pos;
  // The silhouette: the boundary loops, filled even-odd (holes stay open).
  const fill = new Path2D();
  for (const loop of boundaryLoops()) {
    loop.forEach((v, i) => (i ? fill.lineTo(P[2 * v], P[2 * v + 1]) : fill.moveTo(P[2 * v], P[2 * v + 1])));
    fill.closePath();
  }
  const made = { pos: P, fill, loops: boundaryLoops() };
  paths.set(k, made);
  return made;
}

// Draws the ghosts (called by the overlay, under the pins).
export function drawGhosts() {
  const { before, after } = ghostKeys();
  if (!before.length && !after.length) return;
  needPoses([...before, ...after]);
  const opacity = Number($("onion-opacity").value) || 0.6;
  const s = S.view.scale;
  ctx.save();
  ctx.setTransform(s, 0, 0, -s, S.view.x, S.view.y);
  ctx.lineWidth = (2.5 * dpr()) / s;
  ctx.lineJoin = "round";
  const draw = (list, [r, g, b]) => list.forEach((k, i) => {
    if (k === S.frameInfo.keyframe && S.showing === "pose") return;
    const p = pathsOf(k);
    if (!p) return;
    const a = opacity * (1 - i / (list.length + 1));
    ctx.strokeStyle = `rgba(${r},${g},${b},${a})`;
    ctx.stroke(p.fill);
  });
  draw(before, BEFORE);
  draw(after, AFTER);
  ctx.restore();
}

// The settings are the page's (kept across reloads, as a view preference).
const saved = JSON.parse(localStorage.getItem("bdmorph-onion") || "null");
if (saved) {
  $("onion").checked = !!saved.on;
  $("onion-count").value = saved.count;
  $("onion-opacity").value = saved.opacity;
}
for (const id of ["onion", "onion-count", "onion-opacity"]) {
  $(id).addEventListener("input", () => {
    localStorage.setItem("bdmorph-onion", JSON.stringify({ on: $("onion").checked, count: $("onion-count").value, opacity: $("onion-opacity").value }));
    redraw();
  });
}
export function toggleOnion() {
  $("onion").checked = !$("onion").checked;
  $("onion").dispatchEvent(new Event("input"));
}
