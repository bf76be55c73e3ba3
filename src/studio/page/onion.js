// Onion skins: the keyframes before and after what is shown, drawn as tinted ghosts (earlier
// ones red, later ones green, fainter with distance) under the pins, while posing and
// scrubbing. Each ghost is a filled silhouette with its outline, built once per pose (a
// Path2D in the mesh's frame) and drawn with the view's transform: a redraw costs two calls
// per ghost whatever the mesh's size.

import { S, $, ctx, dpr, redraw } from "./view.js";
import { needPoses } from "./net.js";

const BEFORE = [214, 39, 40], AFTER = [44, 160, 44];
const paths = new Map(); // keyframe -> { pos, fill, edge }

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
    const t = S.playing || S.sliding ? S.localTime : st.shown.time;
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

function pathsOf(k) {
  const ghost = S.ghosts.get(k);
  if (!ghost) return null;
  const cached = paths.get(k);
  if (cached && cached.pos === ghost.pos) return cached;
  const P = ghost.pos, F = S.faces;
  const fill = new Path2D(), edge = new Path2D();
  for (let f = 0; f < S.m; f++) {
    const a = 2 * F[3 * f], b = 2 * F[3 * f + 1], c = 2 * F[3 * f + 2];
    fill.moveTo(P[a], P[a + 1]); fill.lineTo(P[b], P[b + 1]); fill.lineTo(P[c], P[c + 1]); fill.closePath();
  }
  for (const [a, b] of S.boundary) { edge.moveTo(P[2 * a], P[2 * a + 1]); edge.lineTo(P[2 * b], P[2 * b + 1]); }
  const made = { pos: P, fill, edge };
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
  ctx.lineWidth = (2 * dpr()) / s;
  ctx.lineJoin = "round";
  const draw = (list, [r, g, b]) => list.forEach((k, i) => {
    if (k === S.frameInfo.keyframe && S.showing === "pose") return;
    const p = pathsOf(k);
    if (!p) return;
    const a = opacity * (1 - i / (list.length + 1));
    ctx.fillStyle = `rgba(${r},${g},${b},${0.22 * a})`;
    ctx.strokeStyle = `rgba(${r},${g},${b},${a})`;
    ctx.fill(p.fill);
    ctx.stroke(p.edge);
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
