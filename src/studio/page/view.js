// The page's mirror of the document (as the server last said it) and the view: zoom, pan,
// and the transforms between the mesh's frame (y up) and the canvas. The page keeps nothing
// else: every edit goes to the server, and what is drawn is what the server says.

export const $ = (id) => document.getElementById(id);

export const KIND_POSE = 1, KIND_MESH = 2, KIND_FRAME = 3, KIND_GHOST = 4, KIND_PAINT = 5, KIND_UPLOAD = 10;

export const S = {
  state: null,            // the last state message
  pins: [],               // the shown keyframe's pins (vertex numbers)
  pinsKeyframe: 0,
  outline: [],            // the document's outline loops
  n: 0, m: 0,
  rest: null,             // Float32Array 2n
  faces: null,            // Uint32Array 3m
  uv: null,               // Float32Array 2n or null
  pieceOf: null,          // Int32Array n: each vertex's piece
  boundary: [],           // [a, b, piece] boundary edges
  pose: null,             // the positions shown (Float32Array 2n)
  dist: null,             // per-triangle distortion shown
  showing: "pose",        // "pose" (a keyframe) or "frame" (the animation at a time)
  frameInfo: { worst: 1, flipped: 0, time: 0, keyframe: -1 },
  view: { scale: 1, x: 0, y: 0, fitScale: 1 },
  texture: null, textureRev: -1,
  seq: 0,                 // the last drag/scrub sequence number sent
  inFlight: 0,            // the sequence number awaited (0: none)
  waiting: null,          // the next drag or scrub, waiting for the one in flight
  drag: null,             // { pin, targets } while dragging pins
  outlineDrag: null,      // { ring, index, point } while dragging an outline point
  keyDrag: null,
  ghosts: new Map(),      // keyframe -> { rev, pos }: keyframe poses (onion skins, thumbnails)
  selected: new Set(),    // the selected pins (vertex numbers) of the keyframe shown
  tool: "drag",           // "drag" (pin and pose), "pins" (place pins, the mesh stays), "depth" or "stiff" (brushes)
  depth: null,            // Int8Array m: the depth level painted on each triangle, or null
  stiffness: null,        // Float32Array m: each triangle's stiffness weight, or null
  order: null,            // Int32Array m: the draw order (by depth), or null for triangle order
  stroke: null,           // a brush stroke in progress
  pendingStroke: null,    // a stroke sent, shown until the server's paint message
  ui: "pose",             // the tab shown: "outline", "pose" or "animate"
  hover: null,            // { v, f } under the cursor, when highlighted
  box: null,              // a selection box being dragged (canvas pixels)
  xform: null,            // a rotation or scaling of the selected pins in progress
  pinMove: null,          // a pin being placed again (pins tool)
  pan: null,
  playing: false,
  connected: false,
  errors: [],             // this page's refused requests, until dismissed
  stats: { perDrawer: [], poseUpdates: 0, frameUpdates: 0, latencies: [], drawMs: [], sent: new Map(), handleMs: 0 },
};
window.studio = S;
// Script errors, kept for the scripted tests to report (and shown to nobody else).
S.pageErrors = [];
window.addEventListener("error", (e) => { S.pageErrors.push(String(e.message)); if (S.pageErrors.length > 20) S.pageErrors.shift(); });

export const canvas = $("view");
export const ctx = canvas.getContext("2d");
export const dpr = () => window.devicePixelRatio || 1;

// World (y up) to canvas pixels and back.
export function toCanvas(x, y) { return [S.view.x + S.view.scale * x, S.view.y - S.view.scale * y]; }
export function toWorld(px, py) { return [(px - S.view.x) / S.view.scale, (S.view.y - py) / S.view.scale]; }
export function eventCanvas(e) {
  const r = canvas.getBoundingClientRect();
  return [(e.clientX - r.left) * dpr(), (e.clientY - r.top) * dpr()];
}
// For scripted tests: the page (CSS pixel) position of a world point, and of vertex v now.
S.toPage = (x, y) => {
  const r = canvas.getBoundingClientRect();
  const [px, py] = toCanvas(x, y);
  return [r.left + px / dpr(), r.top + py / dpr()];
};
S.vertexOnPage = (v) => S.toPage(S.pose[2 * v], S.pose[2 * v + 1]);

// The rest mesh's bounds and size.
export function restBounds() {
  let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
  for (let i = 0; i < S.n; i++) {
    const x = S.rest[2 * i], y = S.rest[2 * i + 1];
    lo = [Math.min(lo[0], x), Math.min(lo[1], y)];
    hi = [Math.max(hi[0], x), Math.max(hi[1], y)];
  }
  return { lo, hi, size: Math.max(hi[0] - lo[0], hi[1] - lo[1]) || 1 };
}

export function fit() {
  if (!S.rest) return;
  const { lo, hi, size } = restBounds();
  const w = canvas.width, h = canvas.height;
  // Room for poses that reach beyond the rest shape.
  S.view.scale = S.view.fitScale = 0.6 * Math.min(w, h) / size;
  S.view.x = w / 2 - S.view.scale * (lo[0] + hi[0]) / 2;
  S.view.y = h / 2 + S.view.scale * (lo[1] + hi[1]) / 2;
  redraw();
}

// Zoom about a canvas point, within 1/50 and 200 times the fitted scale.
export function zoomAt(px, py, k) {
  const fitScale = S.view.fitScale || S.view.scale;
  const scale = Math.min(200 * fitScale, Math.max(fitScale / 50, S.view.scale * k));
  const f = scale / S.view.scale;
  S.view.x = px - f * (px - S.view.x);
  S.view.y = py - f * (py - S.view.y);
  S.view.scale = scale;
  redraw();
}

// A point of the mesh's frame kept within reach of the mesh (ten times its size around it),
// so that a drag off the canvas cannot pull the pose apart.
export function withinReach(p) {
  if (!S.rest) return p;
  const { lo, hi, size } = restBounds();
  const c = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2];
  const d = Math.hypot(p[0] - c[0], p[1] - c[1]), r = 10 * size;
  return d <= r ? p : [c[0] + ((p[0] - c[0]) * r) / d, c[1] + ((p[1] - c[1]) * r) / d];
}

// Redraws once per animation frame, whatever asked for it.
const drawers = [];
let pending = false;
export function onDraw(f) { drawers.push(f); }
export function redraw() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(() => {
    pending = false;
    const t0 = performance.now();
    drawers.forEach((f, i) => {
      const t = performance.now();
      f();
      S.stats.perDrawer[i] = (S.stats.perDrawer[i] || 0) + performance.now() - t;
    });
    S.stats.drawMs.push(performance.now() - t0);
    if (S.stats.drawMs.length > 1000) S.stats.drawMs.shift();
  });
}

export function resize() {
  const r = canvas.getBoundingClientRect();
  canvas.width = Math.max(1, Math.round(r.width * dpr()));
  canvas.height = Math.max(1, Math.round(r.height * dpr()));
  const gl = $("gl");
  gl.width = canvas.width;
  gl.height = canvas.height;
  redraw();
}

// Keyframes and vertices are counted from 1 on the page.
export const nth = (k) => k + 1;
