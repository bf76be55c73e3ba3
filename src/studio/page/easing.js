// The keyframe panel: the selected keyframe's time and the easing of the segment after it,
// edited as a curve (a cubic Bezier from (0,0) to (1,1) whose two handles are dragged, or a
// preset), and previewed as the motion of a dot along the segment. A handle's release sets
// the easing (one undoable step); presets set it at once.

import { S, $, nth, dpr, redraw } from "./view.js";
import { send } from "./net.js";

const curve = $("easing-curve"), preview = $("easing-preview");
const W = 200, H = 150, M = 18; // the curve's box: x in [0,1] maps to [M, W-M], y in [0,1] to [H-M-10, M+10]
const PRESETS = { linear: [0, 0, 1, 1], "ease-in-out": [0.42, 0, 0.58, 1] };
let editing = null; // { handle: 0|1, points } while a handle is dragged

export function parse(easing) {
  if (PRESETS[easing]) return PRESETS[easing].slice();
  const m = /^cubic-bezier[(:]\s*([^,]+),([^,]+),([^,]+),([^,)]+)\)?$/.exec(easing.replace(/\s+/g, ""));
  return m ? m.slice(1, 5).map(Number) : [0, 0, 1, 1];
}
const format = (p) => `cubic-bezier(${p.map((v) => +v.toFixed(3)).join(",")})`;
const toX = (x) => M + x * (W - 2 * M);
const toY = (y) => H - M - 10 - y * (H - 2 * M - 20);
const fromX = (px) => (px - M) / (W - 2 * M);
const fromY = (py) => (H - M - 10 - py) / (H - 2 * M - 20);

// The eased fraction at time fraction t: solves x(s) = t, returns y(s).
export function ease(p, t) {
  const bez = (a, b, s) => 3 * a * s * (1 - s) ** 2 + 3 * b * s * s * (1 - s) + s ** 3;
  let lo = 0, hi = 1;
  for (let i = 0; i < 40; i++) { const mid = (lo + hi) / 2; if (bez(p[0], p[2], mid) < t) lo = mid; else hi = mid; }
  return bez(p[1], p[3], (lo + hi) / 2);
}

function points() {
  const st = S.state;
  if (editing) return editing.points;
  return st ? parse(st.keyframes[st.current].easing) : [0, 0, 1, 1];
}

function drawCurve() {
  const st = S.state;
  if (!st) return;
  const last = st.current === st.keyframes.length - 1;
  const g = curve.getContext("2d");
  if (curve.width !== W * dpr()) { curve.width = W * dpr(); curve.height = H * dpr(); }
  g.setTransform(dpr(), 0, 0, dpr(), 0, 0);
  g.clearRect(0, 0, W, H);
  const css = getComputedStyle(document.body);
  const text = css.getPropertyValue("--text") || "#222", faint = css.getPropertyValue("--faint") || "#999";
  g.strokeStyle = faint;
  g.lineWidth = 1;
  g.strokeRect(toX(0), toY(1), toX(1) - toX(0), toY(0) - toY(1));
  if (last) {
    g.fillStyle = faint;
    g.font = "11px system-ui";
    g.fillText("the last keyframe:", 40, H / 2 - 8);
    g.fillText("no segment after it to ease", 40, H / 2 + 8);
    return;
  }
  const p = points();
  g.strokeStyle = "#1f77b4";
  g.beginPath(); g.moveTo(toX(0), toY(0)); g.lineTo(toX(p[0]), toY(p[1])); g.moveTo(toX(1), toY(1)); g.lineTo(toX(p[2]), toY(p[3])); g.stroke();
  g.strokeStyle = text;
  g.lineWidth = 2;
  g.beginPath(); g.moveTo(toX(0), toY(0));
  g.bezierCurveTo(toX(p[0]), toY(p[1]), toX(p[2]), toY(p[3]), toX(1), toY(1));
  g.stroke();
  g.fillStyle = "#1f77b4";
  for (const [x, y] of [[p[0], p[1]], [p[2], p[3]]]) { g.beginPath(); g.arc(toX(x), toY(y), 5, 0, 2 * Math.PI); g.fill(); }
}

// The dot: eased motion across the preview bar, one second per pass.
function drawPreview(now) {
  const st = S.state;
  const g = preview.getContext("2d");
  const w = 200, h = 18;
  if (preview.width !== w * dpr()) { preview.width = w * dpr(); preview.height = h * dpr(); }
  g.setTransform(dpr(), 0, 0, dpr(), 0, 0);
  g.clearRect(0, 0, w, h);
  if (st && st.current < st.keyframes.length - 1 && !$("key-panel").hidden) {
    const t = ((now / 1000) % 1.4) / 1.2;
    const y = ease(points(), Math.min(t, 1));
    g.fillStyle = "#d26a00";
    g.beginPath(); g.arc(10 + y * (w - 20), h / 2, 6, 0, 2 * Math.PI); g.fill();
  }
  requestAnimationFrame(drawPreview);
}
requestAnimationFrame(drawPreview);

export function drawKeyPanel() {
  const st = S.state;
  if (!st) return;
  const key = st.keyframes[st.current];
  $("key-name").textContent = `${nth(st.current)} of ${st.keyframes.length}`;
  const select = $("key-easing");
  if (document.activeElement !== select) {
    const known = [...select.options].some((o) => o.value === key.easing);
    select.value = known ? key.easing : "custom";
  }
  select.disabled = st.current === st.keyframes.length - 1;
  $("easing-text").textContent = st.current === st.keyframes.length - 1 ? "" : key.easing;
  drawCurve();
}

function handleAt(px, py) {
  const p = points();
  const d = (x, y) => Math.hypot(toX(x) - px, toY(y) - py);
  if (d(p[0], p[1]) <= 9) return 0;
  if (d(p[2], p[3]) <= 9) return 1;
  return -1;
}
curve.addEventListener("mousedown", (e) => {
  const st = S.state;
  if (!st || st.current === st.keyframes.length - 1) return;
  const r = curve.getBoundingClientRect();
  const h = handleAt(e.clientX - r.left, e.clientY - r.top);
  if (h < 0) return;
  e.preventDefault();
  editing = { handle: h, points: points().slice(), keyframe: st.current };
});
window.addEventListener("mousemove", (e) => {
  if (!editing) return;
  const r = curve.getBoundingClientRect();
  const x = Math.min(Math.max(fromX(e.clientX - r.left), 0), 1);
  const y = Math.min(Math.max(fromY(e.clientY - r.top), -1), 2);
  editing.points[2 * editing.handle] = +x.toFixed(3);
  editing.points[2 * editing.handle + 1] = +y.toFixed(3);
  $("easing-text").textContent = format(editing.points);
  drawCurve();
});
window.addEventListener("mouseup", () => {
  if (!editing) return;
  const { points: p, keyframe } = editing;
  editing = null;
  send({ op: "set_easing", keyframe, easing: format(p) });
  redraw();
});
$("key-easing").addEventListener("change", () => {
  if ($("key-easing").value !== "custom") send({ op: "set_easing", keyframe: S.state.current, easing: $("key-easing").value });
});
