// The depth and stiffness brushes (Pose mode), as After Effects' overlap and starch pins:
// - Depth: drag over the mesh to put the triangles under the brush at a level (higher is
//   drawn in front where a pose overlaps itself); Shift+drag puts them back at level 0.
// - Stiff: drag to make the triangles under the brush nearly rigid under every posing
//   method; Shift+drag relaxes them.
// A stroke is painted here as a preview and sent when the button is released: one request,
// one undo step. The painted levels and stiff triangles are shown as an overlay while a
// brush is chosen (or with Display ▸ depth & stiffness).

import { S, $, canvas, ctx, dpr, eventCanvas, toCanvas, redraw } from "./view.js";
import { send } from "./net.js";

// The weight a stiff triangle gets: the smallest round weight that kept a painted region
// within 1% of rigid under every posing method on two meshes (100 did on one only;
// BENCHMARKS.md, "Stiff parts").
export const STIFF_WEIGHT = 1000;

const brushing = () => S.state && S.state.mode === "pose" && (S.tool === "depth" || S.tool === "stiff");
const radius = () => Number($("brush-size").value) * dpr();

// The triangles whose centroid (as shown) is within the brush of canvas point (px, py).
function facesUnder(px, py) {
  const P = S.pose, F = S.faces, r2 = radius() ** 2, out = [];
  for (let f = 0; f < S.m; f++) {
    const a = 2 * F[3 * f], b = 2 * F[3 * f + 1], c = 2 * F[3 * f + 2];
    const [x, y] = toCanvas((P[a] + P[b] + P[c]) / 3, (P[a + 1] + P[b + 1] + P[c + 1]) / 3);
    if ((x - px) ** 2 + (y - py) ** 2 <= r2) out.push(f);
  }
  return out;
}

canvas.addEventListener("mousedown", (e) => {
  if (!brushing() || e.button !== 0 || e.altKey || !S.pose) return;
  const [px, py] = eventCanvas(e);
  S.stroke = { tool: S.tool, erase: e.shiftKey, faces: new Set(facesUnder(px, py)), at: [px, py] };
  redraw();
});
window.addEventListener("mousemove", (e) => {
  const [px, py] = eventCanvas(e);
  if (brushing()) { S.brushAt = [px, py]; redraw(); }
  if (!S.stroke) return;
  for (const f of facesUnder(px, py)) S.stroke.faces.add(f);
  S.stroke.at = [px, py];
  redraw();
});
window.addEventListener("mouseup", () => {
  const s = S.stroke;
  if (!s) return;
  S.stroke = null;
  if (!s.faces.size) { redraw(); return; }
  const faces = [...s.faces];
  if (s.tool === "depth") send({ op: "paint_depth", faces, level: s.erase ? 0 : Number($("depth-level").value) });
  else send({ op: "paint_stiffness", faces, weight: s.erase ? 1 : STIFF_WEIGHT });
  // Kept as the preview until the server's paint message replaces it.
  S.pendingStroke = s;
  redraw();
});
canvas.addEventListener("mouseleave", () => { S.brushAt = null; redraw(); });

$("paint-clear").onclick = () => {
  if (S.tool === "depth") send({ op: "paint_depth", all: true, level: 0 });
  else send({ op: "paint_stiffness", all: true, weight: 1 });
};

// The level a triangle is shown at, the stroke in progress included.
function depthOf(f) {
  for (const s of [S.stroke, S.pendingStroke]) {
    if (s && s.tool === "depth" && s.faces.has(f)) return s.erase ? 0 : Number($("depth-level").value);
  }
  return S.depth ? S.depth[f] : 0;
}
function stiffOf(f) {
  for (const s of [S.stroke, S.pendingStroke]) {
    if (s && s.tool === "stiff" && s.faces.has(f)) return !s.erase;
  }
  return S.stiffness ? S.stiffness[f] > 1 : false;
}

// Depth: warm in front, cool behind, stronger with the level; stiffness: grey hatching.
export function drawPaint() {
  if (!S.pose || !S.faces || !S.state || S.state.mode !== "pose") return;
  const show = brushing() || $("show-paint").checked;
  if (!show) return;
  const P = S.pose, F = S.faces;
  const paths = new Map();
  const showDepth = S.tool === "depth" || $("show-paint").checked;
  const showStiff = S.tool === "stiff" || $("show-paint").checked;
  for (let f = 0; f < S.m; f++) {
    const keys = [];
    if (showDepth) { const d = depthOf(f); if (d) keys.push(`d${d}`); }
    if (showStiff && stiffOf(f)) keys.push("s");
    if (!keys.length) continue;
    for (const key of keys) {
      if (!paths.has(key)) paths.set(key, new Path2D());
      const path = paths.get(key);
      for (let k = 0; k < 3; k++) {
        const v = F[3 * f + k];
        const [x, y] = toCanvas(P[2 * v], P[2 * v + 1]);
        if (k) path.lineTo(x, y); else path.moveTo(x, y);
      }
      path.closePath();
    }
  }
  for (const [key, path] of paths) {
    if (key === "s") {
      ctx.fillStyle = "rgba(60,60,60,0.40)";
    } else {
      const d = Number(key.slice(1)), a = Math.min(0.15 + 0.12 * Math.abs(d), 0.6);
      ctx.fillStyle = d > 0 ? `rgba(255,120,0,${a})` : `rgba(0,110,255,${a})`;
    }
    ctx.fill(path);
  }
  if (brushing() && S.brushAt) {
    ctx.strokeStyle = S.tool === "depth" ? "#e6550d" : "#444";
    ctx.lineWidth = 1.5 * dpr();
    ctx.beginPath(); ctx.arc(S.brushAt[0], S.brushAt[1], radius(), 0, 2 * Math.PI); ctx.stroke();
  }
}

// The painted levels and weights, from the server's paint message.
export function setPaint(depth, stiffness) {
  S.depth = depth;
  S.stiffness = stiffness;
  S.pendingStroke = null;
  // The draw order: triangles by ascending level, stable (as every export draws them).
  S.order = null;
  if (depth && depth.some((d) => d !== depth[0])) {
    const order = Array.from({ length: depth.length }, (_, f) => f);
    order.sort((a, b) => depth[a] - depth[b] || a - b);
    S.order = Int32Array.from(order);
  }
  const painted = (depth ? depth.filter((d) => d !== 0).length : 0);
  const stiff = (stiffness ? stiffness.filter((w) => w > 1).length : 0);
  $("paint-info").textContent = `${painted} triangles with a depth, ${stiff} stiff`;
}
