// The socket to the server: requests out; state, pins, outline, files and frames in. When the
// studio stops, the page says so and tries again every two seconds: a studio restarted in the
// same folder listens on the same port with the same token, and the page picks up its
// document as it is.

import { S, KIND_MESH, KIND_POSE, KIND_FRAME, KIND_GHOST, KIND_PAINT, KIND_UPLOAD, redraw } from "./view.js";

const token = new URLSearchParams(location.search).get("token") || "";
const handlers = { state: [], pins: [], outline: [], files: [], correspondence: [], exists: [], error: [], mesh: [], paint: [], frame: [], open: [], close: [] };
export const on = (type, f) => handlers[type].push(f);
const emit = (type, ...args) => { for (const f of handlers[type]) f(...args); };

let ws = null;
let retry = null;

export function send(request) {
  if (ws && ws.readyState === WebSocket.OPEN) { ws.send(JSON.stringify(request)); return true; }
  emit("error", { message: "not connected to the studio: the request was not sent" });
  return false;
}

// A file's bytes to the workspace: [KIND_UPLOAD, header length] as u32, the header, the bytes.
export function upload(name, bytes, then) {
  const header = new TextEncoder().encode(JSON.stringify({ name, then }));
  const out = new Uint8Array(8 + header.length + bytes.byteLength);
  const words = new DataView(out.buffer);
  words.setUint32(0, KIND_UPLOAD, true);
  words.setUint32(4, header.length, true);
  out.set(header, 8);
  out.set(new Uint8Array(bytes), 8 + header.length);
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(out);
  else emit("error", { message: "not connected to the studio: the file was not sent" });
}

export function textureUrl(rev) { return `texture?token=${encodeURIComponent(token)}&rev=${rev}`; }
// Keyframe k's drawing: its picture, or (uv) its texture coordinates; `rev` only tells
// versions apart.
export function drawingUrl(k, uv, rev) { return `drawing?token=${encodeURIComponent(token)}&k=${k}${uv ? "&uv=1" : ""}&rev=${encodeURIComponent(rev)}`; }
// A picture of the workspace by name.
export function pictureUrl(name) { return `picture?token=${encodeURIComponent(token)}&name=${encodeURIComponent(name)}`; }

export function connect() {
  clearTimeout(retry);
  ws = new WebSocket(`ws://${location.host}/ws?token=${encodeURIComponent(token)}`);
  ws.binaryType = "arraybuffer";
  ws.onopen = () => {
    S.connected = true;
    S.inFlight = 0; S.waiting = null;
    ws.send(JSON.stringify({ op: "hello" }));
    emit("open");
  };
  ws.onclose = () => {
    const was = S.connected;
    S.connected = false;
    S.inFlight = 0; S.waiting = null; S.drag = null;
    asked.clear();
    emit("close", was);
    retry = setTimeout(connect, 2000);
  };
  ws.onmessage = (event) => {
    const t0 = performance.now();
    if (typeof event.data === "string") onText(JSON.parse(event.data));
    else onBinary(event.data);
    S.stats.handleMs += performance.now() - t0;
  };
}

// An answer with `seq` at or past the awaited one settles what was in flight.
function settle(seq) {
  if (S.inFlight && seq >= S.inFlight) {
    S.inFlight = 0;
    flush();
  }
}

function onText(msg) {
  switch (msg.type) {
    case "state": S.state = msg; emit("state", msg); break;
    case "pins": S.pins = msg.pins.slice(); S.pinsKeyframe = msg.keyframe; emit("pins", msg); break;
    case "outline": S.outline = msg.loops; emit("outline", msg); break;
    case "files": emit("files", msg); break;
    case "exists": emit("exists", msg); break;
    case "correspondence": emit("correspondence", msg); break;
    case "ack": settle(msg.seq); break;
    case "error":
      if (msg.seq) settle(msg.seq);
      else if (S.inFlight) { S.inFlight = 0; S.waiting = null; }
      emit("error", msg);
      break;
  }
  redraw();
}

function onBinary(buffer) {
  const head = new DataView(buffer, 0, 16);
  const kind = head.getUint32(0, true);
  if (kind === KIND_MESH) {
    const n = head.getUint32(4, true), m = head.getUint32(8, true), textured = head.getUint32(12, true);
    S.n = n; S.m = m;
    S.rest = new Float32Array(buffer, 16, 2 * n);
    S.faces = new Uint32Array(buffer, 16 + 8 * n, 3 * m);
    S.uv = textured ? new Float32Array(buffer, 16 + 8 * n + 12 * m, 2 * n) : null;
    S.pose = Float32Array.from(S.rest);
    S.dist = new Float32Array(m).fill(1);
    S.ghosts.clear();
    asked.clear();
    emit("mesh");
    redraw();
    return;
  }
  if (kind === KIND_PAINT) {
    const m = head.getUint32(4, true), hasDepth = head.getUint32(8, true), hasStiff = head.getUint32(12, true);
    const depth = hasDepth ? new Int8Array(buffer, 16, m) : null;
    const at = 16 + (hasDepth ? Math.ceil(m / 4) * 4 : 0);
    const stiffness = hasStiff ? new Float32Array(buffer, at, m) : null;
    emit("paint", { depth, stiffness });
    redraw();
    return;
  }
  if (kind === KIND_GHOST) {
    const k = head.getUint32(4, true), n = head.getUint32(8, true), rev = head.getUint32(12, true);
    asked.delete(`${k}:${rev}`);
    if (n !== S.n) return;
    S.ghosts.set(k, { rev, pos: new Float32Array(buffer, 16, 2 * n) });
    S.ghostVersion = (S.ghostVersion || 0) + 1;
    redraw();
    return;
  }
  const frame = new DataView(buffer, 0, 40);
  const seq = frame.getUint32(4, true), n = frame.getUint32(8, true), m = frame.getUint32(12, true);
  if (n !== S.n || m !== S.m) return;
  S.frameInfo = {
    worst: frame.getFloat32(16, true), flipped: frame.getUint32(20, true),
    // The time shown, exactly as the server holds it (f64): the playhead's when idle.
    time: frame.getFloat64(32, true), keyframe: frame.getUint32(28, true),
  };
  S.pose = new Float32Array(buffer, 40, 2 * n);
  S.dist = new Float32Array(buffer, 40 + 8 * n, m);
  S.showing = kind === KIND_POSE ? "pose" : "frame";
  // The keyframe posed is the newest copy of its pose (kept under the revision last said).
  if (kind === KIND_POSE && S.state && S.state.keyframes[S.frameInfo.keyframe]) {
    const old = S.ghosts.get(S.frameInfo.keyframe);
    S.ghosts.set(S.frameInfo.keyframe, { rev: old ? old.rev : S.state.keyframes[S.frameInfo.keyframe].rev, pos: S.pose });
  }
  if (kind === KIND_POSE) S.stats.poseUpdates++;
  if (kind === KIND_FRAME) S.stats.frameUpdates++;
  const sentAt = S.stats.sent.get(seq);
  if (sentAt !== undefined) {
    S.stats.latencies.push(performance.now() - sentAt);
    if (S.stats.latencies.length > 1000) S.stats.latencies.shift();
    S.stats.sent.delete(seq);
  }
  if (seq) settle(seq);
  emit("frame", kind);
  redraw();
}

// Keyframe poses this page lacks (or holds at an old revision) asked for, once each (again
// after two seconds without an answer).
const asked = new Map();
export function needPoses(keyframes) {
  const st = S.state;
  if (!st || !S.connected) return;
  const missing = keyframes.filter((k) => {
    const key = st.keyframes[k], have = S.ghosts.get(k);
    const when = asked.get(`${k}:${key && key.rev}`);
    return key && (!have || have.rev !== key.rev) && !(when && performance.now() - when < 2000);
  });
  if (!missing.length) return;
  for (const k of missing) asked.set(`${k}:${st.keyframes[k].rev}`, performance.now());
  if (asked.size > 1000) asked.clear();
  setTimeout(redraw, 2100);
  send({ op: "ghosts", keyframes: missing.slice(0, 64) });
}

// At most one drag or scrub in flight; a newer one waits in a one-slot mailbox and replaces
// any older waiting one, so the engine never works on stale positions.
export function request(op) {
  S.waiting = op;
  flush();
}
function flush() {
  if (S.inFlight || !S.waiting) return;
  const op = S.waiting;
  S.waiting = null;
  S.seq++;
  op.seq = S.seq;
  if (send(op)) {
    S.inFlight = S.seq;
    S.stats.sent.set(S.seq, performance.now());
    if (S.stats.sent.size > 200) S.stats.sent.delete(S.stats.sent.keys().next().value);
  }
}
S.busy = () => S.inFlight !== 0 || S.waiting !== null;
