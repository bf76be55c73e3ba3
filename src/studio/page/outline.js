// Outline mode: the picture's subject traced (with the background told by transparency, the
// border's colour or a colour given, and a threshold: each change traces again, so the loops
// show what will be meshed), loops edited point by point (every edit an undoable step on the
// server), drawn by clicks, imported from SVG or .poly, then meshed. The new mesh keeps the
// animation: every keyframe is carried over to it. Shift+click selects a whole loop, which
// Delete (or the Delete loop button) removes in one undoable step.

import { S, $, canvas, dpr, eventCanvas, toCanvas, toWorld, redraw } from "./view.js";
import { send, on } from "./net.js";

const outlining = () => S.state && S.state.mode === "outline";

function nearestPoint(px, py, radius) {
  let best = null, bestD = radius * radius;
  S.outline.forEach((loop, li) => loop.forEach(([x, y], pi) => {
    const [qx, qy] = toCanvas(x, y);
    const d = (qx - px) ** 2 + (qy - py) ** 2;
    if (d < bestD) { bestD = d; best = [li, pi]; }
  }));
  return best;
}

// The loop and segment (its first point's index) nearest to a canvas point, within `radius`.
function nearestSegment(px, py, radius) {
  let best = null, bestD = radius;
  const drawing = S.state.drawing;
  S.outline.forEach((loop, li) => loop.forEach((a, pi) => {
    if (li === drawing && pi === loop.length - 1) return;
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

// The loop selected (Shift+click): its place, and its length and first point, so that a
// selection another tab's edit has made stale is dropped rather than misapplied.
S.selectedLoop = null;
export function selectedLoop() {
  const sel = S.selectedLoop, loop = sel && S.outline[sel.ring];
  const fresh = loop && loop.length === sel.n && loop[0][0] === sel.first[0] && loop[0][1] === sel.first[1];
  return fresh ? sel.ring : null;
}
function syncLoopButton() { $("delete-loop").disabled = selectedLoop() === null; }
// Removes the loop selected; whether there was one.
export function deleteSelectedLoop() {
  const ring = selectedLoop();
  if (!outlining() || ring === null) return false;
  S.selectedLoop = null;
  send({ op: "outline_remove_loop", ring });
  syncLoopButton();
  redraw();
  return true;
}
$("delete-loop").onclick = deleteSelectedLoop;
on("outline", () => { if (selectedLoop() === null) S.selectedLoop = null; syncLoopButton(); });

canvas.addEventListener("mousedown", (e) => {
  if (!outlining() || e.button !== 0 || e.altKey) return; // Alt+drag pans (pose.js)
  const [px, py] = eventCanvas(e);
  if (e.shiftKey) {
    const hit = nearestSegment(px, py, 10 * dpr()) || nearestPoint(px, py, 10 * dpr());
    const loop = hit && S.outline[hit[0]];
    S.selectedLoop = loop ? { ring: hit[0], n: loop.length, first: loop[0] } : null;
    syncLoopButton();
    redraw();
    return;
  }
  if (S.selectedLoop) { S.selectedLoop = null; syncLoopButton(); }
  const hit = nearestPoint(px, py, 10 * dpr());
  const drawing = S.state.drawing;
  if (hit && drawing !== null && hit[0] === drawing && hit[1] === 0 && S.outline[drawing].length >= 3) {
    send({ op: "outline_close" }); // the first point clicked again closes the loop
  } else if (hit) {
    S.outlineDrag = { ring: hit[0], index: hit[1], point: S.outline[hit[0]][hit[1]], moved: false };
  } else if (drawing !== null) {
    send({ op: "outline_point", point: toWorld(px, py) });
  } else {
    const on = nearestSegment(px, py, 8 * dpr());
    if (on) {
      const point = toWorld(px, py);
      send({ op: "outline_insert", ring: on[0], index: on[1] + 1, point });
      S.outlineDrag = { ring: on[0], index: on[1] + 1, point, moved: false };
    }
  }
  redraw();
});

window.addEventListener("mousemove", (e) => {
  if (!S.outlineDrag) return;
  const [px, py] = eventCanvas(e);
  S.outlineDrag.point = toWorld(px, py);
  S.outlineDrag.moved = true;
  redraw();
});

window.addEventListener("mouseup", () => {
  const d = S.outlineDrag;
  if (!d) return;
  S.outlineDrag = null;
  if (d.moved) send({ op: "outline_move", ring: d.ring, index: d.index, to: d.point });
  redraw();
});

canvas.addEventListener("contextmenu", (e) => {
  if (!outlining()) return;
  e.preventDefault();
  const [px, py] = eventCanvas(e);
  const hit = nearestPoint(px, py, 10 * dpr());
  if (hit) send({ op: "outline_remove", ring: hit[0], index: hit[1] });
});

const density = () => Math.max(50, Math.round(Number($("density").value) || 2000));

// The background settings as the controls say them.
function pictureSettings() {
  const kind = $("background").value;
  const background = kind === "transparency" ? null : kind === "auto" ? "auto" : $("background-colour").value;
  const threshold = $("threshold-on").checked ? Number($("threshold").value) : null;
  return { background, threshold };
}

export function trace() {
  send({ op: "trace_outline", ...pictureSettings(), vertices: density() });
}

// The controls follow the document's settings (changed in another tab, or undone).
export function syncOutlineTools() {
  const st = S.state;
  if (!st) return;
  const p = st.picture_settings;
  if (document.activeElement !== $("background")) {
    $("background").value = p.background === null ? "transparency" : p.background === "auto" ? "auto" : "colour";
    if (p.background && p.background.startsWith("#") && p.background.length === 7) $("background-colour").value = p.background;
  }
  if (document.activeElement !== $("threshold")) {
    $("threshold-on").checked = p.threshold !== null;
    if (p.threshold !== null) $("threshold").value = p.threshold;
  }
  $("threshold-readout").textContent = $("threshold-on").checked ? Number($("threshold").value).toFixed(2) : "default";
  $("background-colour").hidden = $("background").value !== "colour";
  $("trace").disabled = !st.picture;
  for (const id of ["background", "threshold", "threshold-on"]) $(id).disabled = !st.picture;
}

export function outlineMode() {
  send({ op: "mode", mode: "outline" });
  // A picture with no outline yet is traced at once.
  if (S.state && S.state.picture && S.outline.length === 0) trace();
}
$("outline-mode").onclick = outlineMode;
$("trace").onclick = trace;
// Each change traces again with the controls' settings (the document's follow).
for (const id of ["background", "background-colour", "threshold", "threshold-on"]) {
  $(id).addEventListener("change", () => {
    $("background-colour").hidden = $("background").value !== "colour";
    trace();
  });
}
$("threshold").addEventListener("input", () => { $("threshold-readout").textContent = Number($("threshold").value).toFixed(2); });
$("new-loop").onclick = () => send({ op: "outline_new_loop" });
$("clear-outline").onclick = () => send({ op: "outline_set", loops: [] });
$("create-mesh").onclick = () => {
  if (!S.outline.some((l) => l.length >= 3)) { S.errors.push("draw or trace a loop first"); redraw(); return; }
  send({ op: "mesh_outline", vertices: density() });
};
$("import-outline").onclick = () => $("outline-file").click();
$("outline-file").addEventListener("change", async () => {
  const file = $("outline-file").files[0];
  if (!file) return;
  send({ op: "import_outline", name: file.name, text: await file.text(), vertices: density() });
  $("outline-file").value = "";
});
