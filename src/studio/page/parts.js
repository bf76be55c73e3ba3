// The parts panel, for a character made from a layered picture: one row per part, front
// first (as layer panels list them), with its name (a click selects the pins on it), an eye
// (shown or hidden while editing; every export draws every part), a lock (its vertices take no
// new pin) and two arrows that change the draw order. Hiding, locking and the draw order are
// each an undoable step on the server, saved with the project. The joints are drawn on the
// canvas as small rings, where two parts are tied.
//
// The joints tool (Pose mode, J): a click where two parts overlap ties the two drawn in front
// there; a joint dragged is placed again where it is let go (between the same parts); a
// right-click on a joint removes it. Each is one undoable step on the server, which makes the
// vertices a joint needs (see src/studio/rig.rs).

import { S, $, canvas, ctx, dpr, eventCanvas, toCanvas, toWorld, redraw } from "./view.js";
import { send } from "./net.js";

S.hiddenParts = new Set();   // part names hidden (the document's, as the state says)
S.lockedParts = new Set();   // part names whose vertices take no new pin
S.faceHidden = null;         // Uint8Array m: 1 for a triangle of a hidden part, or null
S.vertexLocked = null;       // Uint8Array n: 1 for a vertex of a locked part, or null

// The per-triangle and per-vertex masks from the sets, for the drawing and the picking.
function syncMasks() {
  const parts = (S.state && S.state.parts) || [];
  S.hiddenParts = new Set(parts.filter((p) => p.hidden).map((p) => p.name));
  S.lockedParts = new Set(parts.filter((p) => p.locked).map((p) => p.name));
  S.faceHidden = null;
  S.vertexLocked = null;
  for (const p of parts) {
    if (S.hiddenParts.has(p.name)) {
      if (!S.faceHidden) S.faceHidden = new Uint8Array(S.m);
      S.faceHidden.fill(1, p.faces[0], Math.min(p.faces[1], S.m));
    }
    if (S.lockedParts.has(p.name)) {
      if (!S.vertexLocked) S.vertexLocked = new Uint8Array(S.n);
      S.vertexLocked.fill(1, p.vertices[0], Math.min(p.vertices[1], S.n));
    }
  }
}

function button(text, title, onclick, on = false) {
  const b = document.createElement("button");
  b.textContent = text;
  b.title = title;
  b.className = "part-button" + (on ? " on" : "");
  b.onclick = onclick;
  return b;
}

// Moves part `i` (in the document's bottom-first list) `by` places towards the front.
function move(i, by) {
  const n = S.state.parts.length;
  const order = Array.from({ length: n }, (_, k) => k);
  const j = i + by;
  if (j < 0 || j >= n) return;
  [order[i], order[j]] = [order[j], order[i]];
  send({ op: "part_order", order });
}

export function drawPartsPanel() {
  const parts = (S.state && S.state.parts) || null;
  $("parts-panel").hidden = !parts || S.state.mode === "outline";
  syncMasks();
  if (!parts) return;
  const key = JSON.stringify(parts);
  if ($("part-list").dataset.key === key) return;
  $("part-list").dataset.key = key;
  const list = $("part-list");
  list.replaceChildren();
  // Front first, as layer panels list them.
  for (let i = parts.length - 1; i >= 0; i--) {
    const p = parts[i];
    const row = document.createElement("div");
    row.className = "part-row";
    row.dataset.part = p.name;
    const name = document.createElement("span");
    name.className = "part-name";
    name.textContent = p.name;
    name.title = "Select the pins on this part (to turn or scale them with the handles)";
    name.onclick = () => {
      S.selected.clear();
      for (const v of S.pins) if (v >= p.vertices[0] && v < p.vertices[1]) S.selected.add(v);
      S.flash = { text: S.selected.size ? `${S.selected.size} pins on ${p.name} selected` : `no pins on ${p.name}: pin it to pose it`, until: performance.now() + 2500 };
      setTimeout(redraw, 2600);
      redraw();
    };
    const hidden = !!p.hidden, locked = !!p.locked;
    row.append(
      button(hidden ? "◌" : "●", hidden ? "Show this part" : "Hide this part while editing (exports draw every part)", () => {
        send({ op: "part_flags", part: i, hidden: !hidden, locked });
      }, !hidden),
      button(locked ? "⊠" : "□", locked ? "Unlock: its vertices take pins again" : "Lock: its vertices take no new pin", () => {
        send({ op: "part_flags", part: i, hidden, locked: !locked });
      }, locked),
      name,
      button("▲", "Draw in front of the part above", () => move(i, 1)),
      button("▼", "Draw behind the part below", () => move(i, -1)),
    );
    list.append(row);
  }
}

const jointsTool = () => S.state && S.state.mode === "pose" && S.tool === "joints" && S.state.parts;
S.jointDrag = null;          // { joint, from, at } (canvas pixels) while a joint is dragged

// The joint whose ring is nearest a canvas point, within `radius`, or -1.
function nearestJoint(px, py, radius) {
  const joints = (S.state && S.state.joints) || [];
  let best = -1, bestD = radius * radius;
  joints.forEach(([a], i) => {
    if (a >= S.n) return;
    const [x, y] = toCanvas(S.pose[2 * a], S.pose[2 * a + 1]);
    const d = (x - px) ** 2 + (y - py) ** 2;
    if (d < bestD) { bestD = d; best = i; }
  });
  return best;
}

canvas.addEventListener("mousedown", (e) => {
  if (!jointsTool() || e.button !== 0 || e.altKey || !S.pose) return;
  const [px, py] = eventCanvas(e);
  const j = nearestJoint(px, py, 12 * dpr());
  if (j >= 0) { S.jointDrag = { joint: j, from: [px, py], at: [px, py] }; redraw(); return; }
  send({ op: "joint_add", at: toWorld(px, py) });
});
window.addEventListener("mousemove", (e) => {
  if (!S.jointDrag) return;
  S.jointDrag.at = eventCanvas(e);
  redraw();
});
window.addEventListener("mouseup", () => {
  const d = S.jointDrag;
  if (!d) return;
  S.jointDrag = null;
  if (Math.hypot(d.at[0] - d.from[0], d.at[1] - d.from[1]) > 3 * dpr()) {
    send({ op: "joint_move", joint: d.joint, to: toWorld(...d.at) });
  }
  redraw();
});
canvas.addEventListener("contextmenu", (e) => {
  if (!jointsTool()) return;
  e.preventDefault();
  const [px, py] = eventCanvas(e);
  const j = nearestJoint(px, py, 12 * dpr());
  if (j >= 0) send({ op: "joint_remove", joint: j });
});

// The joints: a ring where two parts are tied (larger, to be grabbed, with the joints tool;
// the one dragged where the mouse is).
export function drawJoints() {
  const joints = S.state && S.state.joints;
  const tool = jointsTool();
  if (!joints || !(tool || $("joints-shown").checked) || !S.pose) return;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.lineWidth = 2 * dpr();
  joints.forEach(([a], i) => {
    if (a >= S.n) return;
    const dragged = S.jointDrag && S.jointDrag.joint === i;
    const [x, y] = dragged ? S.jointDrag.at : toCanvas(S.pose[2 * a], S.pose[2 * a + 1]);
    ctx.strokeStyle = "rgba(255, 255, 255, 0.95)";
    ctx.fillStyle = tool ? "rgba(255, 140, 0, 0.9)" : "rgba(20, 20, 20, 0.6)";
    ctx.beginPath();
    ctx.arc(x, y, (tool ? 7 : 4) * dpr(), 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
  });
}

$("joints-shown").addEventListener("change", redraw);
