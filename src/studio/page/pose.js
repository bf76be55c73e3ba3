// Posing with the mouse: a click on a vertex pins it (a frame between keyframes, when one is
// shown, becomes a keyframe with that pin: the click acts on what is shown); dragging a pin
// moves it and the mesh follows; a right-click removes a pin. Wheel zooms about the cursor,
// the middle button or Shift+drag pans.

import { S, $, canvas, dpr, eventCanvas, toCanvas, toWorld, withinReach, zoomAt, redraw } from "./view.js";
import { send, request } from "./net.js";

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

const posing = () => S.state && S.state.mode === "pose";

canvas.addEventListener("contextmenu", (e) => {
  e.preventDefault();
  if (!posing() || S.showing !== "pose") return;
  const [px, py] = eventCanvas(e);
  const i = nearestPin(px, py, 12 * dpr());
  if (i >= 0) send({ op: "pin_remove", vertex: S.pins[i] });
});

canvas.addEventListener("mousedown", (e) => {
  canvas.focus();
  const [px, py] = eventCanvas(e);
  if (e.button === 1 || (e.button === 0 && e.shiftKey)) {
    S.pan = { px, py, x: S.view.x, y: S.view.y };
    e.preventDefault();
    return;
  }
  if (!posing() || e.button !== 0 || !S.pose) return;
  let i = S.showing === "pose" ? nearestPin(px, py, 12 * dpr()) : -1;
  if (i < 0) {
    const v = nearestVertex(px, py, 14 * dpr());
    if (v < 0) return;
    // On a frame between keyframes the server makes a keyframe of it with this one pin.
    const pins = S.showing === "pose" ? [...S.pins, v] : [v];
    send({ op: "pin_add", vertex: v });
    S.pins = pins;
    S.showing = "pose";
    i = pins.length - 1;
  }
  S.drag = { pin: i, pins: S.pins.slice(), targets: S.pins.map((v) => [S.pose[2 * v], S.pose[2 * v + 1]]) };
  redraw();
});

window.addEventListener("mousemove", (e) => {
  const [px, py] = eventCanvas(e);
  if (S.pan) {
    S.view.x = S.pan.x + (px - S.pan.px);
    S.view.y = S.pan.y + (py - S.pan.py);
    redraw();
    return;
  }
  if (!S.drag) return;
  S.drag.targets[S.drag.pin] = withinReach(toWorld(px, py));
  request({ op: "drag", pins: S.drag.pins, targets: S.drag.targets.map((t) => t.slice()) });
});

window.addEventListener("mouseup", () => {
  if (S.pan) { S.pan = null; return; }
  if (!S.drag) return;
  S.drag = null;
  send({ op: "drag_end" });
  redraw();
});

canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  const [px, py] = eventCanvas(e);
  zoomAt(px, py, Math.exp(-e.deltaY * 0.0015));
}, { passive: false });

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
