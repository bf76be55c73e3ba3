// What is drawn over the mesh on the 2D canvas: each piece's outline (in its own colour, so
// that specks and separate parts show), rings around flipped triangles, the pins, the anchor
// edges, the outline being edited; and the whole mesh when WebGL is missing.

import { S, $, ctx, canvas, dpr, toCanvas, onDraw } from "./view.js";
import { GL } from "./gl.js";
import { drawGhosts } from "./onion.js";
import { drawPins, drawAids, drawPinPanel } from "./pose.js";
import { drawJoints } from "./parts.js";
import { drawPaint } from "./paint.js";

const PIECE_COLOURS = ["#1f77b4", "#e6550d", "#31a354", "#756bb1", "#d62728", "#8c564b", "#e377c2", "#17becf"];

// Each vertex's piece and the boundary edges of every piece, from the triangles.
export function computePieces() {
  const n = S.n, F = S.faces;
  const parent = new Int32Array(n);
  for (let v = 0; v < n; v++) parent[v] = v;
  const find = (v) => { while (parent[v] !== v) { parent[v] = parent[parent[v]]; v = parent[v]; } return v; };
  for (let f = 0; f < S.m; f++) {
    const a = find(F[3 * f]);
    for (let k = 1; k < 3; k++) {
      const b = find(F[3 * f + k]);
      if (a !== b) parent[Math.max(a, b)] = Math.min(a, b);
    }
  }
  const number = new Map();
  S.pieceOf = new Int32Array(n).fill(-1);
  for (let f = 0; f < S.m; f++) for (let k = 0; k < 3; k++) {
    const v = F[3 * f + k], r = find(v);
    if (!number.has(r)) number.set(r, number.size);
    S.pieceOf[v] = number.get(r);
  }
  // A boundary edge is used by one triangle only (in one direction).
  const seen = new Map();
  for (let f = 0; f < S.m; f++) for (let k = 0; k < 3; k++) {
    const a = F[3 * f + k], b = F[3 * f + (k + 1) % 3];
    const key = a < b ? a * n + b : b * n + a;
    seen.set(key, seen.has(key) ? -1 : a * n + b);
  }
  S.boundary = [];
  for (const v of seen.values()) if (v >= 0) {
    const a = Math.floor(v / n), b = v % n;
    S.boundary.push([a, b, S.pieceOf[a]]);
  }
  S.pieceCount = number.size;
}

function strokeEdges(P) {
  const F = S.faces;
  ctx.beginPath();
  for (let i = 0; i < S.m; i++) {
    const f = S.order ? S.order[i] : i;
    const [ax, ay] = toCanvas(P[2 * F[3 * f]], P[2 * F[3 * f] + 1]);
    const [bx, by] = toCanvas(P[2 * F[3 * f + 1]], P[2 * F[3 * f + 1] + 1]);
    const [cx, cy] = toCanvas(P[2 * F[3 * f + 2]], P[2 * F[3 * f + 2] + 1]);
    ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.lineTo(cx, cy); ctx.closePath();
  }
  ctx.stroke();
}

// The mesh on the 2D canvas (when WebGL is missing): flat, or coloured flipped.
function drawMesh2d() {
  const F = S.faces, P = S.pose;
  ctx.fillStyle = "#b9d3ee";
  for (let f = 0; f < S.m; f++) {
    const [ax, ay] = toCanvas(P[2 * F[3 * f]], P[2 * F[3 * f] + 1]);
    const [bx, by] = toCanvas(P[2 * F[3 * f + 1]], P[2 * F[3 * f + 1] + 1]);
    const [cx, cy] = toCanvas(P[2 * F[3 * f + 2]], P[2 * F[3 * f + 2] + 1]);
    ctx.fillStyle = S.dist[f] < 1e30 ? "#b9d3ee" : "#ff00cc";
    ctx.beginPath(); ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.lineTo(cx, cy); ctx.closePath(); ctx.fill();
  }
  if ($("edges").checked) { ctx.strokeStyle = "rgba(255,255,255,0.6)"; ctx.lineWidth = 1; strokeEdges(P); }
}

function drawPieces() {
  if (!$("pieces").checked || !S.boundary.length) return;
  const P = S.pose;
  ctx.lineWidth = 2 * dpr();
  const many = S.pieceCount > 1;
  for (let p = 0; p < Math.min(S.pieceCount, 64); p++) {
    ctx.strokeStyle = many ? PIECE_COLOURS[p % PIECE_COLOURS.length] : "rgba(30,30,30,0.5)";
    ctx.beginPath();
    for (const [a, b, piece] of S.boundary) {
      if (piece !== p) continue;
      const [ax, ay] = toCanvas(P[2 * a], P[2 * a + 1]);
      const [bx, by] = toCanvas(P[2 * b], P[2 * b + 1]);
      ctx.moveTo(ax, ay); ctx.lineTo(bx, by);
    }
    ctx.stroke();
  }
}

// A ring around each flipped triangle (at most 300), so even a tiny fold shows.
function drawFlips() {
  const F = S.faces, P = S.pose;
  let shown = 0;
  ctx.strokeStyle = "#ff00cc";
  ctx.lineWidth = 2 * dpr();
  for (let f = 0; f < S.m && shown < 300; f++) {
    if (S.dist[f] < 1e30) continue;
    shown++;
    let x = 0, y = 0;
    for (let k = 0; k < 3; k++) { x += P[2 * F[3 * f + k]] / 3; y += P[2 * F[3 * f + k] + 1] / 3; }
    const [cx, cy] = toCanvas(x, y);
    ctx.beginPath(); ctx.arc(cx, cy, 9 * dpr(), 0, 2 * Math.PI); ctx.stroke();
  }
}

function drawAnchors() {
  if (!$("anchor").checked || !S.state) return;
  const P = S.pose;
  ctx.strokeStyle = "#ff7f0e";
  ctx.lineWidth = 4 * dpr();
  for (const [a, b] of S.state.anchors) {
    const [ax, ay] = toCanvas(P[2 * a], P[2 * a + 1]);
    const [bx, by] = toCanvas(P[2 * b], P[2 * b + 1]);
    ctx.beginPath(); ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.stroke();
  }
}

function drawOutline() {
  if (!S.state || S.state.mode !== "outline") return;
  // The whole picture, half transparent, in its pixels' frame (where the outline is traced),
  // over the rest mesh; the loops on top.
  ctx.fillStyle = "rgba(255,255,255,0.35)";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  if (S.texture && S.state.picture) {
    const [w, h] = S.state.picture;
    const [x0, y0] = toCanvas(0, h);
    ctx.globalAlpha = 0.5;
    ctx.drawImage(S.texture, x0, y0, w * S.view.scale, h * S.view.scale);
    ctx.globalAlpha = 1;
  }
  const drawing = S.state.drawing;
  S.outline.forEach((loop, li) => {
    const points = loop.map((p, pi) => {
      const d = S.outlineDrag;
      return d && d.ring === li && d.index === pi ? d.point : p;
    });
    if (!points.length) return;
    const selected = S.selectedLoop && S.selectedLoop.ring === li && li !== drawing;
    ctx.strokeStyle = li === drawing ? "#e6550d" : selected ? "#ff00cc" : "#1f4ea8";
    ctx.lineWidth = (selected ? 4 : 2) * dpr();
    ctx.beginPath();
    points.forEach((p, i) => { const [x, y] = toCanvas(p[0], p[1]); if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y); });
    if (li !== drawing) ctx.closePath();
    if (selected) { ctx.fillStyle = "rgba(255,0,204,0.25)"; ctx.fill("evenodd"); }
    ctx.stroke();
    ctx.fillStyle = li === drawing ? "#e6550d" : "#1f4ea8";
    const every = Math.max(1, Math.floor(points.length / 400));
    points.forEach((p, i) => {
      if (i % every) return;
      const [x, y] = toCanvas(p[0], p[1]);
      ctx.beginPath(); ctx.arc(x, y, (i === 0 && li === drawing ? 5 : 3) * dpr(), 0, 2 * Math.PI); ctx.fill();
    });
  });
}

onDraw(() => {
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (GL.ready()) GL.draw();
  if (!S.pose || !S.faces) return;
  if (!GL.ready() && S.state && S.state.mode !== "outline") drawMesh2d();
  if (S.state && S.state.mode === "outline") { drawOutline(); return; }
  drawGhosts();
  drawPaint();
  drawPieces();
  drawFlips();
  drawAnchors();
  drawJoints();
  drawAids();
  drawPins();
  drawPinPanel();
});
