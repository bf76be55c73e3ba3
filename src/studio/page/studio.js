// bdmorph studio: the page. Plain JavaScript module on a 2D canvas; the engine is the server,
// reached over one WebSocket (JSON requests; JSON state and binary f32 frames back).
//
// At most one drag and one scrub are in flight: a newer position waits in a one-slot mailbox
// and replaces any older waiting one, so the engine never works on stale positions.

const token = new URLSearchParams(location.search).get("token") || "";
const $ = (id) => document.getElementById(id);
const canvas = $("view");
const ctx = canvas.getContext("2d");
// The mesh is drawn by WebGL 2 when the browser has it (thousands of triangles per frame);
// otherwise on the 2D canvas, which also draws the pins in both cases.
const glCanvas = $("gl");
const gl = glCanvas.getContext("webgl2", { antialias: false, premultipliedAlpha: false });

const KIND_POSE = 1, KIND_MESH = 2, KIND_FRAME = 3;

const S = {
  state: null,            // the last JSON state
  n: 0, m: 0,
  rest: null,             // Float32Array 2n
  faces: null,            // Uint32Array 3m
  uv: null,               // Float32Array 2n or null
  pose: null,             // the positions shown
  dist: null,             // per-triangle distortion shown
  showing: "pose",        // "pose" (the keyframe being posed) or "frame" (the animation)
  frameInfo: { worst: 1, flipped: 0, time: 0 },
  pins: [],
  drag: null,             // { pin, targets } while dragging
  dragSeq: 0, dragInFlight: false, dragWaiting: null,
  keyDrag: null,
  scrubSeq: 0, scrubInFlight: false, scrubWaiting: null,
  view: { scale: 1, x: 0, y: 0 },
  pan: null,
  playing: false, playStart: 0, playFrom: 0,
  texture: null,
  outline: { on: false, loops: [], drawing: null, dragPoint: null },
  stats: { poseUpdates: 0, frameUpdates: 0, latencies: [], drawMs: [], sent: new Map() },
};
window.studio = S;

// ---- the socket -------------------------------------------------------------------------
const ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}`);
ws.binaryType = "arraybuffer";
const send = (request) => { if (ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(request)); };
ws.onopen = () => send({ op: "hello" });
ws.onclose = () => status("disconnected: reload the page once the studio runs again", true);
ws.onmessage = (event) => {
  if (typeof event.data === "string") onState(JSON.parse(event.data));
  else onBinary(event.data);
};

function status(text, error = false) {
  const el = $("status");
  el.textContent = text;
  el.classList.toggle("error", error);
}

function onState(msg) {
  if (msg.type === "error") { status(msg.message, true); settleAll(); return; }
  if (msg.type === "outline") {
    S.outline.loops = msg.loops;
    S.outline.drawing = null;
    status(`traced: ${msg.loops.length} loops, ${msg.loops.reduce((a, l) => a + l.length, 0)} points; drag points to edit, then Create mesh`);
    draw();
    return;
  }
  if (msg.type !== "state") return;
  S.state = msg;
  S.pins = msg.keyframes[msg.current].pins.slice();
  const method = $("method");
  if (document.activeElement !== method) method.value = msg.method.name;
  syncParam();
  $("undo").disabled = !msg.can_undo;
  $("redo").disabled = !msg.can_redo;
  $("texture").disabled = !msg.textured;
  if (msg.textured && !S.texture) {
    // A picture's project opens showing the picture.
    $("texture").checked = true;
    loadTexture();
  }
  const key = msg.keyframes[msg.current];
  if (document.activeElement !== $("key-time")) $("key-time").value = key.time;
  $("key-easing").value = key.easing;
  if (document.activeElement !== $("fps")) $("fps").value = msg.fps;
  drawTimeline();
  if (msg.message) status(msg.message, msg.message.startsWith("error"));
  else showStats();
  if (msg.message && msg.message.startsWith("error")) settleAll();
  draw();
}

function settleAll() {
  S.dragInFlight = false; S.scrubInFlight = false;
  flushDrag(); flushScrub();
}

function onBinary(buffer) {
  const head = new DataView(buffer, 0, 32);
  const kind = head.getUint32(0, true);
  if (kind === KIND_MESH) {
    const n = head.getUint32(4, true), m = head.getUint32(8, true), textured = head.getUint32(12, true);
    S.n = n; S.m = m;
    S.rest = new Float32Array(buffer, 16, 2 * n);
    S.faces = new Uint32Array(buffer, 16 + 8 * n, 3 * m);
    S.uv = textured ? new Float32Array(buffer, 16 + 8 * n + 12 * m, 2 * n) : null;
    S.pose = Float32Array.from(S.rest);
    S.dist = new Float32Array(m).fill(1);
    GL.setMesh();
    if (S.texture && GL.setTexture) GL.setTexture(S.texture);
    if (S.outline.on) setOutlineMode(false);
    S.pins = [];
    fit();
    return;
  }
  const seq = head.getUint32(4, true), n = head.getUint32(8, true), m = head.getUint32(12, true);
  if (n !== S.n || m !== S.m) return;
  S.frameInfo = { worst: head.getFloat32(16, true), flipped: head.getUint32(20, true), time: head.getFloat32(24, true) };
  S.pose = new Float32Array(buffer, 32, 2 * n);
  S.dist = new Float32Array(buffer, 32 + 8 * n, m);
  const sentAt = S.stats.sent.get(`${kind}:${seq}`);
  if (sentAt !== undefined) {
    S.stats.latencies.push(performance.now() - sentAt);
    if (S.stats.latencies.length > 1000) S.stats.latencies.shift();
    S.stats.sent.delete(`${kind}:${seq}`);
  }
  if (kind === KIND_POSE) {
    S.showing = "pose";
    S.stats.poseUpdates++;
    if (seq !== 0 && seq === S.dragSeq) { S.dragInFlight = false; flushDrag(); }
  } else if (kind === KIND_FRAME) {
    S.showing = "frame";
    S.stats.frameUpdates++;
    if (seq === S.scrubSeq) { S.scrubInFlight = false; flushScrub(); }
  }
  showStats();
  draw();
}

function showStats() {
  const st = S.state;
  if (!st) return;
  const what = S.showing === "frame" ? `frame at ${S.frameInfo.time.toFixed(2)} s` : `keyframe ${st.current + 1} of ${st.keyframes.length}`;
  const worst = Number.isFinite(S.frameInfo.worst) ? S.frameInfo.worst.toFixed(3) : "∞";
  const lat = S.stats.latencies;
  const recent = lat.slice(-30);
  const mean = recent.length ? (recent.reduce((a, b) => a + b, 0) / recent.length).toFixed(1) : "–";
  status(`${what} · ${st.vertices} vertices, ${st.faces} triangles · largest distortion ${worst}, ${S.frameInfo.flipped} flipped · ${S.pins.length} pins · ${mean} ms per update`);
}

// ---- view ---------------------------------------------------------------------------------
function resize() {
  const r = canvas.getBoundingClientRect();
  const dpr = window.devicePixelRatio || 1;
  canvas.width = Math.max(1, Math.round(r.width * dpr));
  canvas.height = Math.max(1, Math.round(r.height * dpr));
  glCanvas.width = canvas.width;
  glCanvas.height = canvas.height;
  draw();
}
window.addEventListener("resize", resize);

function fit() {
  if (!S.rest) return;
  let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
  for (let i = 0; i < S.n; i++) {
    const x = S.rest[2 * i], y = S.rest[2 * i + 1];
    lo = [Math.min(lo[0], x), Math.min(lo[1], y)];
    hi = [Math.max(hi[0], x), Math.max(hi[1], y)];
  }
  const w = canvas.width, h = canvas.height;
  const span = Math.max(hi[0] - lo[0], hi[1] - lo[1]) || 1;
  // Room for poses that reach beyond the rest shape.
  S.view.scale = 0.6 * Math.min(w, h) / span;
  S.view.x = w / 2 - S.view.scale * (lo[0] + hi[0]) / 2;
  S.view.y = h / 2 + S.view.scale * (lo[1] + hi[1]) / 2;
  draw();
}

// World (y up) to canvas pixels and back.
const dpr = () => window.devicePixelRatio || 1;
function toCanvas(x, y) { return [S.view.x + S.view.scale * x, S.view.y - S.view.scale * y]; }
function toWorld(px, py) { return [(px - S.view.x) / S.view.scale, (S.view.y - py) / S.view.scale]; }
function eventCanvas(e) {
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

// ---- drawing ------------------------------------------------------------------------------
const SHADES = 24;
// Viridis-like ramp from 1 (dark) to the scale's top (yellow), on a log scale.
function shade(i) {
  const t = i / (SHADES - 1);
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  const s = t * (stops.length - 1), k = Math.min(stops.length - 2, Math.floor(s)), f = s - k;
  const c = stops[k].map((a, j) => Math.round(a + f * (stops[k + 1][j] - a)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}
const RAMP = Array.from({ length: SHADES }, (_, i) => shade(i));

function draw() {
  const started = performance.now();
  paint();
  const ms = performance.now() - started;
  S.stats.drawMs.push(ms);
  if (S.stats.drawMs.length > 1000) S.stats.drawMs.shift();
}

function paint() {
  const w = canvas.width, h = canvas.height;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, w, h);
  if (S.outline.on) { paintOutline(); return; }
  if (!S.pose || !S.faces) return;
  if (GL.ready()) {
    GL.draw();
    drawPins();
    return;
  }
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, w, h);
  const P = S.pose, F = S.faces, D = S.dist;
  const sx = S.view.scale, ox = S.view.x, oy = S.view.y;
  if ($("overlay").checked && S.rest) {
    ctx.strokeStyle = "rgba(200,120,0,0.35)";
    ctx.lineWidth = 1;
    strokeEdges(S.rest, sx, ox, oy);
  }
  if ($("texture").checked && S.texture && S.uv) {
    drawTextured(P, sx, ox, oy);
  } else {
    // Triangles grouped by shade: one path per shade.
    const colours = $("colours").checked;
    let top = 0;
    for (let f = 0; f < S.m; f++) if (Number.isFinite(D[f])) top = Math.max(top, D[f]);
    const scale = Math.log(Math.max(top, 1.05));
    const buckets = Array.from({ length: SHADES + 1 }, () => []);
    for (let f = 0; f < S.m; f++) {
      const d = D[f];
      if (!Number.isFinite(d)) buckets[SHADES].push(f);
      else if (!colours) buckets[0].push(f);
      else buckets[Math.min(SHADES - 1, Math.floor((SHADES - 1) * Math.log(Math.max(d, 1)) / scale + 0.5))].push(f);
    }
    for (let b = 0; b <= SHADES; b++) {
      const list = buckets[b];
      if (!list.length) continue;
      ctx.beginPath();
      for (const f of list) {
        const a = F[3 * f], c = F[3 * f + 1], e = F[3 * f + 2];
        ctx.moveTo(ox + sx * P[2 * a], oy - sx * P[2 * a + 1]);
        ctx.lineTo(ox + sx * P[2 * c], oy - sx * P[2 * c + 1]);
        ctx.lineTo(ox + sx * P[2 * e], oy - sx * P[2 * e + 1]);
        ctx.closePath();
      }
      ctx.fillStyle = b === SHADES ? "#e0102a" : (colours ? RAMP[b] : "#b9d3ee");
      ctx.fill();
    }
  }
  if ($("edges").checked) {
    ctx.strokeStyle = "rgba(255,255,255,0.35)";
    ctx.lineWidth = 1;
    strokeEdges(P, sx, ox, oy);
  }
  drawPins();
}

function drawPins() {
  const P = S.pose;
  if ($("anchor").checked && S.state && S.state.anchors) {
    ctx.lineWidth = 4 * dpr();
    ctx.strokeStyle = "#e0102a";
    ctx.fillStyle = "#e0102a";
    for (const [a, b] of S.state.anchors) {
      const [x0, y0] = toCanvas(P[2 * a], P[2 * a + 1]);
      const [x1, y1] = toCanvas(P[2 * b], P[2 * b + 1]);
      ctx.beginPath(); ctx.moveTo(x0, y0); ctx.lineTo(x1, y1); ctx.stroke();
      ctx.beginPath(); ctx.arc(x0, y0, 5 * dpr(), 0, 2 * Math.PI); ctx.fill();
    }
  }
  if (S.showing === "pose") {
    for (let i = 0; i < S.pins.length; i++) {
      const v = S.pins[i];
      const [px, py] = toCanvas(P[2 * v], P[2 * v + 1]);
      ctx.beginPath();
      ctx.arc(px, py, 6 * dpr(), 0, 2 * Math.PI);
      ctx.fillStyle = S.drag && S.drag.pin === i ? "#ff3b00" : "#ff9d00";
      ctx.fill();
      ctx.lineWidth = 2;
      ctx.strokeStyle = "#222";
      ctx.stroke();
    }
  }
}

// The outline editor: the picture under the loops, each loop's points as small squares.
function paintOutline() {
  ctx.fillStyle = "#fff";
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  const pic = S.state && S.state.picture;
  if (S.texture && pic) {
    const [x0, y0] = toCanvas(0, pic[1]);
    ctx.globalAlpha = 0.6;
    ctx.drawImage(S.texture, x0, y0, S.view.scale * pic[0], S.view.scale * pic[1]);
    ctx.globalAlpha = 1;
  }
  S.outline.loops.forEach((loop, li) => {
    if (!loop.length) return;
    ctx.beginPath();
    loop.forEach(([x, y], i) => {
      const [px, py] = toCanvas(x, y);
      if (i === 0) ctx.moveTo(px, py); else ctx.lineTo(px, py);
    });
    if (li !== S.outline.drawing) ctx.closePath();
    ctx.lineWidth = 2 * dpr();
    ctx.strokeStyle = li === S.outline.drawing ? "#d26a00" : "#1a4fa0";
    ctx.stroke();
    ctx.fillStyle = ctx.strokeStyle;
    for (const [x, y] of loop) {
      const [px, py] = toCanvas(x, y);
      ctx.fillRect(px - 3 * dpr(), py - 3 * dpr(), 6 * dpr(), 6 * dpr());
    }
  });
}

function nearestOutlinePoint(px, py, radius) {
  let best = null, bestD = radius * radius;
  S.outline.loops.forEach((loop, li) => loop.forEach(([x, y], pi) => {
    const [qx, qy] = toCanvas(x, y);
    const d = (qx - px) ** 2 + (qy - py) ** 2;
    if (d < bestD) { bestD = d; best = [li, pi]; }
  }));
  return best;
}

// The loop and segment (its first point's index) nearest to a canvas point, within `radius`.
function nearestOutlineSegment(px, py, radius) {
  let best = null, bestD = radius;
  S.outline.loops.forEach((loop, li) => loop.forEach((a, pi) => {
    if (li === S.outline.drawing && pi === loop.length - 1) return;
    const [ax, ay] = toCanvas(...a);
    const [bx, by] = toCanvas(...loop[(pi + 1) % loop.length]);
    const [dx, dy] = [bx - ax, by - ay];
    const len2 = dx * dx + dy * dy || 1;
    const s = Math.max(0, Math.min(1, ((px - ax) * dx + (py - ay) * dy) / len2));
    const d = Math.hypot(ax + s * dx - px, ay + s * dy - py);
    if (d < bestD) { bestD = d; best = [li, pi]; }
  }));
  return best;
}

function setOutlineMode(on) {
  S.outline.on = on;
  $("outline-mode").classList.toggle("on", on);
  $("outline-tools").hidden = !on;
  if (on && S.outline.loops.length === 0 && S.state && S.state.picture) send({ op: "trace_outline" });
  if (on) status("outline: Trace picture, or New loop and click its points (click the first to close it; a loop inside another is a hole); drag a point to move it, click a segment to add one, right-click a point to remove it; then Create mesh");
  draw();
}

function strokeEdges(P, sx, ox, oy) {
  const F = S.faces;
  ctx.beginPath();
  for (let f = 0; f < S.m; f++) {
    const a = F[3 * f], c = F[3 * f + 1], e = F[3 * f + 2];
    ctx.moveTo(ox + sx * P[2 * a], oy - sx * P[2 * a + 1]);
    ctx.lineTo(ox + sx * P[2 * c], oy - sx * P[2 * c + 1]);
    ctx.lineTo(ox + sx * P[2 * e], oy - sx * P[2 * e + 1]);
    ctx.closePath();
  }
  ctx.stroke();
}

// Each triangle drawn with the picture through the affine map its corners define.
function drawTextured(P, sx, ox, oy) {
  const img = S.texture, W = img.width, H = img.height, F = S.faces, U = S.uv;
  for (let f = 0; f < S.m; f++) {
    const v = [F[3 * f], F[3 * f + 1], F[3 * f + 2]];
    const p = v.map((k) => [ox + sx * P[2 * k], oy - sx * P[2 * k + 1]]);
    const t = v.map((k) => [U[2 * k] * W, (1 - U[2 * k + 1]) * H]);
    const den = (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
    if (Math.abs(den) < 1e-12) continue;
    const a = ((p[1][0] - p[0][0]) * (t[2][1] - t[0][1]) - (p[2][0] - p[0][0]) * (t[1][1] - t[0][1])) / den;
    const b = ((p[1][1] - p[0][1]) * (t[2][1] - t[0][1]) - (p[2][1] - p[0][1]) * (t[1][1] - t[0][1])) / den;
    const c = ((p[2][0] - p[0][0]) * (t[1][0] - t[0][0]) - (p[1][0] - p[0][0]) * (t[2][0] - t[0][0])) / den;
    const d = ((p[2][1] - p[0][1]) * (t[1][0] - t[0][0]) - (p[1][1] - p[0][1]) * (t[2][0] - t[0][0])) / den;
    const e = p[0][0] - a * t[0][0] - c * t[0][1];
    const g = p[0][1] - b * t[0][0] - d * t[0][1];
    ctx.save();
    ctx.beginPath();
    ctx.moveTo(p[0][0], p[0][1]); ctx.lineTo(p[1][0], p[1][1]); ctx.lineTo(p[2][0], p[2][1]);
    ctx.closePath();
    ctx.clip();
    ctx.setTransform(a, b, c, d, e, g);
    ctx.drawImage(img, 0, 0);
    ctx.restore();
  }
  ctx.setTransform(1, 0, 0, 1, 0, 0);
}

function loadTexture() {
  const img = new Image();
  img.onload = () => {
    S.texture = img;
    if (GL.setTexture && S.faces) GL.setTexture(img);
    draw();
  };
  img.src = `texture.png?token=${encodeURIComponent(token)}`;
}


// ---- WebGL 2 ------------------------------------------------------------------------------
// Triangles are expanded (three corners each) so that each carries its own distortion and a
// barycentric coordinate: the fragment shader colours by the distortion ramp (or samples the
// texture) and draws the edges from the barycentrics, in one pass.
const GL = (() => {
  if (!gl) return { kind: "2d", ready: () => false, setMesh() {}, draw() {} };
  const vs = `#version 300 es
    in vec2 position; in float distortion; in vec3 bary; in vec2 uv;
    uniform vec3 view; uniform vec2 size;
    out float d; out vec3 b; out vec2 t;
    void main() {
      vec2 p = vec2(view.y + view.x * position.x, view.z - view.x * position.y);
      gl_Position = vec4(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y, 0.0, 1.0);
      d = distortion; b = bary; t = uv;
    }`;
  const fs = `#version 300 es
    precision highp float;
    in float d; in vec3 b; in vec2 t;
    uniform float top; uniform int mode; uniform bool edges; uniform float alpha; uniform sampler2D picture;
    out vec4 colour;
    vec3 ramp(float s) {
      vec3 c0 = vec3(68, 1, 84) / 255.0, c1 = vec3(59, 82, 139) / 255.0, c2 = vec3(33, 145, 140) / 255.0,
           c3 = vec3(94, 201, 98) / 255.0, c4 = vec3(253, 231, 37) / 255.0;
      s = clamp(s, 0.0, 1.0) * 4.0;
      if (s < 1.0) return mix(c0, c1, s);
      if (s < 2.0) return mix(c1, c2, s - 1.0);
      if (s < 3.0) return mix(c2, c3, s - 2.0);
      return mix(c3, c4, s - 3.0);
    }
    void main() {
      vec3 c;
      if (!(d < 1e30)) c = vec3(0.88, 0.06, 0.16);
      else if (mode == 1) c = ramp(log(max(d, 1.0)) / log(max(top, 1.05)));
      else if (mode == 2) { vec4 s = texture(picture, t); c = mix(vec3(1.0), s.rgb, s.a); }
      else c = vec3(0.725, 0.827, 0.933);
      float a = alpha;
      if (edges) {
        vec3 w = fwidth(b);
        vec3 e = smoothstep(vec3(0.0), 1.2 * w, b);
        float edge = 1.0 - min(min(e.x, e.y), e.z);
        c = mix(c, vec3(1.0), 0.35 * edge);
        if (alpha < 1.0) a = alpha * edge;
      }
      colour = vec4(c, a);
    }`;
  const compile = (type, src) => {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, src);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
    return sh;
  };
  let program;
  try {
    program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, vs));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  } catch (e) {
    console.warn("WebGL unavailable, drawing on the 2D canvas:", e);
    return { kind: "2d", ready: () => false, setMesh() {}, draw() {} };
  }
  const loc = (n) => gl.getAttribLocation(program, n);
  const uni = (n) => gl.getUniformLocation(program, n);
  const buffers = { position: gl.createBuffer(), distortion: gl.createBuffer(), bary: gl.createBuffer(), uv: gl.createBuffer(), rest: gl.createBuffer() };
  let corners = 0, pos = null, dis = null, restPos = null, texture = null;
  const attrib = (buffer, name, size) => {
    const l = loc(name);
    if (l < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.enableVertexAttribArray(l);
    gl.vertexAttribPointer(l, size, gl.FLOAT, false, 0, 0);
  };
  const expand = (src, out) => {
    const F = S.faces;
    for (let c = 0; c < corners; c++) {
      const v = F[c];
      out[2 * c] = src[2 * v];
      out[2 * c + 1] = src[2 * v + 1];
    }
  };
  return {
    kind: "webgl2",
    ready: () => corners > 0,
    setMesh() {
      corners = 3 * S.m;
      pos = new Float32Array(2 * corners);
      dis = new Float32Array(corners);
      restPos = new Float32Array(2 * corners);
      const bary = new Float32Array(3 * corners);
      for (let c = 0; c < corners; c++) bary[3 * c + (c % 3)] = 1;
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.bary);
      gl.bufferData(gl.ARRAY_BUFFER, bary, gl.STATIC_DRAW);
      const uv = new Float32Array(2 * corners);
      if (S.uv) {
        for (let c = 0; c < corners; c++) {
          const v = S.faces[c];
          uv[2 * c] = S.uv[2 * v];
          uv[2 * c + 1] = 1 - S.uv[2 * v + 1];
        }
      }
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.uv);
      gl.bufferData(gl.ARRAY_BUFFER, uv, gl.STATIC_DRAW);
      expand(S.rest, restPos);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.rest);
      gl.bufferData(gl.ARRAY_BUFFER, restPos, gl.STATIC_DRAW);
    },
    setTexture(img) {
      texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, img);
      gl.generateMipmap(gl.TEXTURE_2D);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
    },
    draw() {
      gl.viewport(0, 0, glCanvas.width, glCanvas.height);
      gl.clearColor(1, 1, 1, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.useProgram(program);
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
      gl.uniform3f(uni("view"), S.view.scale, S.view.x, S.view.y);
      gl.uniform2f(uni("size"), glCanvas.width, glCanvas.height);
      let top = 1;
      for (let f = 0; f < S.m; f++) if (S.dist[f] < 1e30) top = Math.max(top, S.dist[f]);
      gl.uniform1f(uni("top"), top);
      const textured = $("texture").checked && texture && S.uv;
      gl.uniform1i(uni("mode"), textured ? 2 : $("colours").checked ? 1 : 0);
      if (texture) { gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, texture); gl.uniform1i(uni("picture"), 0); }
      attrib(buffers.bary, "bary", 3);
      attrib(buffers.uv, "uv", 2);
      if ($("overlay").checked) {
        // The first keyframe's (rest) edges, faint, under the pose.
        attrib(buffers.rest, "position", 2);
        const l = loc("distortion");
        if (l >= 0) { gl.disableVertexAttribArray(l); gl.vertexAttrib1f(l, 1); }
        gl.uniform1i(uni("edges"), 1);
        gl.uniform1f(uni("alpha"), 0.35);
        gl.uniform1i(uni("mode"), 0);
        gl.drawArrays(gl.TRIANGLES, 0, corners);
        gl.uniform1i(uni("mode"), textured ? 2 : $("colours").checked ? 1 : 0);
      }
      expand(S.pose, pos);
      for (let c = 0; c < corners; c++) dis[c] = S.dist[(c / 3) | 0];
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.position);
      gl.bufferData(gl.ARRAY_BUFFER, pos, gl.DYNAMIC_DRAW);
      attrib(buffers.position, "position", 2);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.distortion);
      gl.bufferData(gl.ARRAY_BUFFER, dis, gl.DYNAMIC_DRAW);
      attrib(buffers.distortion, "distortion", 1);
      gl.uniform1i(uni("edges"), $("edges").checked ? 1 : 0);
      gl.uniform1f(uni("alpha"), 1);
      gl.drawArrays(gl.TRIANGLES, 0, corners);
    },
  };
})();
S.renderer = GL.kind;

// ---- posing -------------------------------------------------------------------------------
function nearestVertex(px, py, radius) {
  let best = -1, bestD = radius * radius;
  for (let v = 0; v < S.n; v++) {
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
function pinTargets() { return S.pins.map((v) => [S.pose[2 * v], S.pose[2 * v + 1]]); }

function requestDrag(targets) {
  S.dragWaiting = targets;
  flushDrag();
}
function flushDrag() {
  if (S.dragInFlight || !S.dragWaiting) return;
  const targets = S.dragWaiting;
  S.dragWaiting = null;
  S.dragInFlight = true;
  S.dragSeq++;
  S.stats.sent.set(`${KIND_POSE}:${S.dragSeq}`, performance.now());
  send({ op: "drag", seq: S.dragSeq, targets });
}

canvas.addEventListener("contextmenu", (e) => {
  e.preventDefault();
  if (S.outline.on) {
    const [px, py] = eventCanvas(e);
    const hit = nearestOutlinePoint(px, py, 10 * dpr());
    if (!hit) return;
    const [li, pi] = hit;
    S.outline.loops[li].splice(pi, 1);
    if (S.outline.loops[li].length < 3 && li !== S.outline.drawing) {
      S.outline.loops.splice(li, 1);
      if (S.outline.drawing !== null && S.outline.drawing > li) S.outline.drawing--;
    }
    draw();
    return;
  }
  if (S.showing !== "pose") return;
  const [px, py] = eventCanvas(e);
  const i = nearestPin(px, py, 12 * dpr());
  if (i >= 0) {
    S.pins.splice(i, 1);
    send({ op: "pins", pins: S.pins });
    draw();
  }
});

canvas.addEventListener("mousedown", (e) => {
  canvas.focus();
  const [px, py] = eventCanvas(e);
  if (e.button === 1 || (e.button === 0 && e.shiftKey)) {
    S.pan = { px, py, x: S.view.x, y: S.view.y };
    e.preventDefault();
    return;
  }
  if (e.button === 0 && S.outline.on) {
    const hit = nearestOutlinePoint(px, py, 10 * dpr());
    const d = S.outline.drawing;
    if (hit && d !== null && hit[0] === d && hit[1] === 0 && S.outline.loops[d].length >= 3) {
      S.outline.drawing = null; // the first point clicked again closes the loop
    } else if (hit) S.outline.dragPoint = hit;
    else if (d !== null) S.outline.loops[S.outline.drawing].push(toWorld(px, py));
    else {
      const on = nearestOutlineSegment(px, py, 8 * dpr());
      if (on) {
        S.outline.loops[on[0]].splice(on[1] + 1, 0, toWorld(px, py));
        S.outline.dragPoint = [on[0], on[1] + 1];
      }
    }
    draw();
    return;
  }
  if (e.button !== 0 || !S.pose) return;
  if (S.showing !== "pose") { send({ op: "select", keyframe: S.state.current }); return; }
  let i = nearestPin(px, py, 12 * dpr());
  if (i < 0) {
    const v = nearestVertex(px, py, 14 * dpr());
    if (v < 0) return;
    S.pins.push(v);
    i = S.pins.length - 1;
    send({ op: "pins", pins: S.pins });
  }
  S.drag = { pin: i, targets: pinTargets() };
  draw();
});

window.addEventListener("mousemove", (e) => {
  const [px, py] = eventCanvas(e);
  if (S.pan) {
    S.view.x = S.pan.x + (px - S.pan.px);
    S.view.y = S.pan.y + (py - S.pan.py);
    draw();
    return;
  }
  if (S.outline.dragPoint) {
    const [li, pi] = S.outline.dragPoint;
    S.outline.loops[li][pi] = toWorld(px, py);
    draw();
    return;
  }
  if (!S.drag) return;
  S.drag.targets[S.drag.pin] = toWorld(px, py);
  requestDrag(S.drag.targets.map((t) => t.slice()));
});

window.addEventListener("mouseup", () => {
  if (S.pan) { S.pan = null; return; }
  if (S.outline.dragPoint) { S.outline.dragPoint = null; return; }
  if (!S.drag) return;
  S.drag = null;
  send({ op: "drag_end" });
  draw();
});

canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const [px, py] = eventCanvas(e);
  const k = Math.exp(-e.deltaY * 0.0015);
  S.view.x = px - k * (px - S.view.x);
  S.view.y = py - k * (py - S.view.y);
  S.view.scale *= k;
  draw();
}, { passive: false });

window.addEventListener("keydown", (e) => {
  if (e.target instanceof HTMLInputElement) return;
  if ((e.ctrlKey || e.metaKey) && e.key === "z") { send({ op: "undo" }); e.preventDefault(); }
  if ((e.ctrlKey || e.metaKey) && (e.key === "y" || (e.shiftKey && e.key === "Z"))) { send({ op: "redo" }); e.preventDefault(); }
  if (e.key === " ") { togglePlay(); e.preventDefault(); }
});

// ---- controls -----------------------------------------------------------------------------
function syncParam() {
  const st = S.state;
  if (!st) return;
  const name = $("method").value;
  const label = $("param-label");
  const input = $("param");
  label.style.visibility = name === "arap" ? "hidden" : "visible";
  label.firstChild.textContent = name === "bounded" ? "K " : "weight ";
  if (document.activeElement !== input) input.value = name === "bounded" ? st.method.max_distortion : st.method.weight;
}
$("method").addEventListener("change", () => {
  send({ op: "method", name: $("method").value });
});
$("param").addEventListener("change", () => {
  const value = Number($("param").value);
  const name = $("method").value;
  send({ op: "method", name, ...(name === "bounded" ? { max_distortion: value } : { weight: value }) });
});
$("undo").onclick = () => send({ op: "undo" });
$("redo").onclick = () => send({ op: "redo" });
$("reset").onclick = () => send({ op: "reset" });
$("unpin").onclick = () => { S.pins = []; send({ op: "pins", pins: [] }); draw(); };
for (const id of ["edges", "colours", "texture", "overlay", "anchor"]) $(id).addEventListener("change", draw);
$("outline-mode").onclick = () => setOutlineMode(!S.outline.on);
$("trace").onclick = () => send({ op: "trace_outline" });
$("new-loop").onclick = () => {
  S.outline.loops = S.outline.loops.filter((l) => l.length >= 3);
  S.outline.loops.push([]);
  S.outline.drawing = S.outline.loops.length - 1;
  draw();
};
$("clear-outline").onclick = () => { S.outline.loops = []; S.outline.drawing = null; draw(); };
const density = () => Math.max(50, Math.round(Number($("density").value) || 2000));
$("create-mesh").onclick = () => {
  const loops = S.outline.loops.filter((l) => l.length >= 3);
  if (!loops.length) { status("draw or trace a loop first", true); return; }
  status("meshing…");
  send({ op: "mesh_outline", loops, vertices: density() });
};
$("import-outline").onclick = () => $("outline-file").click();
$("outline-file").addEventListener("change", async () => {
  const file = $("outline-file").files[0];
  if (!file) return;
  status(`meshing ${file.name}…`);
  send({ op: "import_outline", name: file.name, text: await file.text(), vertices: density() });
  $("outline-file").value = "";
});
$("load-key").onclick = () => $("load-file").click();
$("load-file").addEventListener("change", async () => {
  const file = $("load-file").files[0];
  if (!file) return;
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  status(`reading ${file.name}…`);
  send({ op: "load_keyframe", name: file.name, text: await file.text(), time: Math.round((last + 1) * 1000) / 1000 });
  $("load-file").value = "";
});
$("fit").onclick = fit;
$("save").onclick = () => send({ op: "save", name: $("save-name").value });
$("export-format").addEventListener("change", () => {
  const f = $("export-format").value;
  const ext = { gif: ".gif", mp4: ".mp4", png: ".png", html: ".html", obj: "", still: ".png" }[f];
  $("export-name").value = f === "still" ? "frame.png" : "animation" + (f === "obj" ? "-frames" : ext);
});
$("export").onclick = () => {
  status("exporting…");
  const format = $("export-format").value;
  const request = { op: "export", format, name: $("export-name").value };
  // A screenshot is of what is shown: the scrubbed frame, or the keyframe being posed.
  if (format === "still" && S.showing === "frame") request.time = sliderTime();
  send(request);
};
// A new keyframe one second after the last: a copy of the first ("add") or of the one being
// posed ("clone").
function addKeyframe(copy) {
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  send({ op: "add_keyframe", time: Math.round((last + 1) * 1000) / 1000, copy });
}
$("add-key").onclick = () => addKeyframe(0);
$("clone-key").onclick = () => addKeyframe(S.state.current);
$("frame-key").onclick = () => send({ op: "frame_to_keyframe", time: sliderTime() });
$("delete-key").onclick = () => send({ op: "delete_keyframe", keyframe: S.state.current });
$("key-earlier").onclick = () => {
  const k = S.state.current;
  if (k > 0) send({ op: "move_keyframe", keyframe: k, to: k - 1 });
};
$("key-later").onclick = () => {
  const k = S.state.current;
  if (k + 1 < S.state.keyframes.length) send({ op: "move_keyframe", keyframe: k, to: k + 1 });
};
$("fps").addEventListener("change", () => send({ op: "fps", fps: Number($("fps").value) }));
$("key-time").addEventListener("change", () => send({ op: "set_time", keyframe: S.state.current, time: Number($("key-time").value) }));
$("key-easing").addEventListener("change", () => send({ op: "set_easing", keyframe: S.state.current, easing: $("key-easing").value }));

function drawTimeline() {
  const st = S.state, keys = $("keys");
  keys.textContent = "";
  const duration = Math.max(st.duration, 1e-9);
  st.keyframes.forEach((k, i) => {
    const el = document.createElement("div");
    el.className = "key" + (i === st.current ? " current" : "");
    el.style.left = `${(100 * k.time) / duration}%`;
    el.title = `keyframe ${i + 1} at ${k.time} s (${k.easing})`;
    el.dataset.index = String(i);
    el.onmousedown = (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      S.keyDrag = { index: i, startX: e.clientX, moved: false };
    };
    keys.appendChild(el);
  });
}

// A key on the timeline: a click selects it, a drag moves it in time (between its neighbours).
function keyDragTime(clientX) {
  const st = S.state, k = S.keyDrag.index;
  const r = $("keys").getBoundingClientRect();
  const duration = Math.max(st.duration, 1e-9);
  let time = Math.max(0, ((clientX - r.left) / r.width) * duration);
  const after = st.keyframes[k - 1].time;
  const before = k + 1 < st.keyframes.length ? st.keyframes[k + 1].time : Infinity;
  const gap = 1e-3;
  time = Math.min(Math.max(time, after + gap), before - gap);
  return Math.round(time * 1000) / 1000;
}
window.addEventListener("mousemove", (e) => {
  if (!S.keyDrag || S.keyDrag.index === 0) return;
  if (Math.abs(e.clientX - S.keyDrag.startX) < 3 && !S.keyDrag.moved) return;
  S.keyDrag.moved = true;
  const el = $("keys").children[S.keyDrag.index];
  const time = keyDragTime(e.clientX);
  el.style.left = `${Math.min(100, (100 * time) / Math.max(S.state.duration, 1e-9))}%`;
  el.title = `${time} s`;
});
window.addEventListener("mouseup", (e) => {
  if (!S.keyDrag) return;
  const { index, moved } = S.keyDrag;
  if (moved) {
    send({ op: "set_time", keyframe: index, time: keyDragTime(e.clientX) });
    send({ op: "select", keyframe: index });
  } else send({ op: "select", keyframe: index });
  S.keyDrag = null;
});

// ---- playback -----------------------------------------------------------------------------
function sliderTime() {
  const st = S.state;
  return st ? (Number($("time").value) / 1000) * st.duration : 0;
}
function requestScrub(time) {
  S.scrubWaiting = time;
  flushScrub();
}
function flushScrub() {
  if (S.scrubInFlight || S.scrubWaiting === null) return;
  const time = S.scrubWaiting;
  S.scrubWaiting = null;
  S.scrubInFlight = true;
  S.scrubSeq++;
  S.stats.sent.set(`${KIND_FRAME}:${S.scrubSeq}`, performance.now());
  send({ op: "scrub", seq: S.scrubSeq, time });
}
$("time").addEventListener("input", () => {
  const time = sliderTime();
  $("time-readout").textContent = `${time.toFixed(2)} s`;
  requestScrub(time);
});

function togglePlay() {
  if (!S.state || S.state.keyframes.length < 2) { status("add a second keyframe to play", true); return; }
  S.playing = !S.playing;
  $("play").textContent = S.playing ? "Pause" : "Play";
  if (S.playing) {
    S.playStart = performance.now();
    S.playFrom = sliderTime() >= S.state.duration ? 0 : sliderTime();
    requestAnimationFrame(tick);
  }
}
$("play").onclick = togglePlay;
let lastTick = 0;
function tick(now) {
  if (!S.playing) return;
  const st = S.state;
  const fps = Math.max(1, Number($("fps").value) || 25);
  if (now - lastTick >= 1000 / fps - 1) {
    lastTick = now;
    let time = S.playFrom + (now - S.playStart) / 1000;
    if (time > st.duration) {
      if ($("loop").checked) { S.playStart = now; S.playFrom = 0; time = 0; }
      else { time = st.duration; S.playing = false; $("play").textContent = "Play"; }
    }
    $("time").value = String(Math.round((1000 * time) / Math.max(st.duration, 1e-9)));
    $("time-readout").textContent = `${time.toFixed(2)} s`;
    requestScrub(time);
  }
  requestAnimationFrame(tick);
}

resize();
