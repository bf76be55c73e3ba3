// "Drawing…": another drawing of the subject made a keyframe. The rest picture and the chosen
// drawing side by side; a click on one and then on the other places a numbered pair of points
// that must correspond (optional: the outlines are matched automatically; pairs on the
// outlines pin that matching, pairs inside pin the mesh). Pairs are listed and deletable, and
// kept in this browser per drawing until the keyframe is made, so a reload loses none. "Make
// keyframe" lays the mesh over the drawing in the background (the job bar shows it); the
// keyframe comes as one undoable step, with its picture cross-faded in playback and exports.

import { S, $, redraw } from "./view.js";
import { send, upload, on, pictureUrl } from "./net.js";

const SIDE = 360;               // each picture's box, in CSS pixels
const stored = (name) => `bdmorph-drawing-pairs:${name}`;
const D = { name: "", pairs: [], pending: null, drawing: null, listing: false, preview: null, asked: null };

// The correspondence the keyframe would use, asked for again (at most every 300 ms) when the
// drawing or the pairs change: matching coloured marks around both outlines.
let previewTimer = null;
function askPreview() {
  clearTimeout(previewTimer);
  D.preview = null;
  if (!D.name) return;
  previewTimer = setTimeout(() => {
    D.asked = D.name;
    send({ op: "drawing_preview", name: D.name, pairs: D.pairs.map((p) => [p.a, p.b]) });
    $("drawing-status").textContent = "matching the outlines…";
  }, 300);
}
on("correspondence", (msg) => {
  if (msg.name !== D.name) return;
  D.asked = null;
  D.preview = msg.loops;
  draw();
});
// A drawing that cannot be matched says why here.
on("error", (msg) => {
  if (!D.asked || !$("drawing-dialog").open) return;
  D.asked = null;
  D.problem = msg.message;
  msg.handled = true;
  draw();
});

function keep() {
  if (!D.name) return;
  try { localStorage.setItem(stored(D.name), JSON.stringify(D.pairs)); } catch (_) { /* private mode: kept in the page */ }
}
function restore(name) {
  try {
    const pairs = JSON.parse(localStorage.getItem(stored(name)) || "[]");
    return Array.isArray(pairs) ? pairs.filter((p) => p && p.a && p.b) : [];
  } catch (_) { return []; }
}

// Where a picture of w x h pixels sits in its box: scale and offset.
function placing(w, h) {
  const k = Math.min(SIDE / w, SIDE / h);
  return { k, x: (SIDE - k * w) / 2, y: (SIDE - k * h) / 2 };
}

function drawSide(canvas, img, which) {
  const dpr = window.devicePixelRatio || 1;
  canvas.width = SIDE * dpr; canvas.height = SIDE * dpr;
  canvas.style.width = `${SIDE}px`; canvas.style.height = `${SIDE}px`;
  const c = canvas.getContext("2d");
  c.setTransform(dpr, 0, 0, dpr, 0, 0);
  c.fillStyle = "#f4f4f4";
  c.fillRect(0, 0, SIDE, SIDE);
  if (!img || !img.naturalWidth) {
    c.fillStyle = "#666";
    c.font = "13px sans-serif";
    c.fillText(which === "a" ? "no rest picture" : "choose a drawing", 12, 22);
    return;
  }
  const p = placing(img.naturalWidth, img.naturalHeight);
  c.drawImage(img, p.x, p.y, p.k * img.naturalWidth, p.k * img.naturalHeight);
  const dot = (q, label, hollow) => {
    const x = p.x + p.k * q[0], y = p.y + p.k * q[1];
    c.beginPath();
    c.arc(x, y, 8, 0, 2 * Math.PI);
    // Yellow ringed in black: seen on light, dark and saturated drawings alike.
    c.fillStyle = hollow ? "rgba(255,255,255,0.85)" : "#ffd400";
    c.fill();
    c.lineWidth = 2;
    c.strokeStyle = "#000";
    c.setLineDash(hollow ? [3, 2] : []);
    c.stroke();
    c.setLineDash([]);
    c.fillStyle = "#000";
    c.font = "bold 11px sans-serif";
    c.textAlign = "center";
    c.textBaseline = "middle";
    c.fillText(label, x, y + 0.5);
  };
  // The outline's correspondence: the same colour at the same place of both outlines.
  for (const loop of D.preview || []) {
    loop.forEach((pq, i) => {
      const q = pq[which === "a" ? 0 : 1];
      c.beginPath();
      c.arc(p.x + p.k * q[0], p.y + p.k * q[1], 4, 0, 2 * Math.PI);
      c.fillStyle = `hsl(${(360 * i) / loop.length}, 90%, 50%)`;
      c.fill();
      c.lineWidth = 1.5;
      c.strokeStyle = "#fff";
      c.stroke();
    });
  }
  D.pairs.forEach((pair, i) => dot(pair[which], String(i + 1), false));
  if (D.pending && D.pending[which]) dot(D.pending[which], String(D.pairs.length + 1), true);
}

function draw() {
  drawSide($("drawing-rest"), S.texture, "a");
  drawSide($("drawing-new"), D.drawing, "b");
  const list = $("drawing-pairs");
  list.textContent = "";
  D.pairs.forEach((pair, i) => {
    const li = document.createElement("li");
    const f = (q) => `(${Math.round(q[0])}, ${Math.round(q[1])})`;
    li.append(`${f(pair.a)} → ${f(pair.b)} `);
    const x = document.createElement("button");
    x.textContent = "×";
    x.title = `Delete pair ${i + 1}`;
    x.onclick = () => { D.pairs.splice(i, 1); changed(); };
    li.appendChild(x);
    list.appendChild(li);
  });
  const hint = D.pending ? `pair ${D.pairs.length + 1}: now click the same point on the ${D.pending.a ? "drawing" : "rest picture"}` :
    D.problem ? D.problem :
    (D.pairs.length ? `${D.pairs.length} pair${D.pairs.length === 1 ? "" : "s"}. ` : "No pairs: the outlines are matched automatically. ") +
    (D.preview ? "Marks of one colour are matched points of the two outlines." : "");
  $("drawing-status").textContent = hint;
  $("drawing-status").classList.toggle("problem", !!D.problem && !D.pending);
  $("drawing-make").disabled = !D.name || !D.drawing || !S.texture || !!D.problem;
}

// A click on one side: the pending pair's point there (in the picture's pixels).
function clicked(which, img, e) {
  if (!img || !img.naturalWidth) return;
  const r = e.target.getBoundingClientRect();
  const p = placing(img.naturalWidth, img.naturalHeight);
  const x = (e.clientX - r.left - p.x) / p.k, y = (e.clientY - r.top - p.y) / p.k;
  if (x < 0 || y < 0 || x > img.naturalWidth || y > img.naturalHeight) return;
  D.pending = { ...(D.pending || {}), [which]: [x, y] };
  if (D.pending.a && D.pending.b) {
    D.pairs.push(D.pending);
    D.pending = null;
    changed();
    return;
  }
  draw();
}
$("drawing-rest").addEventListener("click", (e) => clicked("a", S.texture, e));
$("drawing-new").addEventListener("click", (e) => clicked("b", D.drawing, e));

// The pairs changed: kept, and the correspondence asked for again.
function changed() {
  keep();
  D.problem = null;
  askPreview();
  draw();
}

function choose(name) {
  D.name = name;
  D.pairs = name ? restore(name) : [];
  D.pending = null;
  D.drawing = null;
  D.problem = null;
  askPreview();
  draw();
  if (!name) return;
  const img = new Image();
  img.onload = () => { if (D.name === name) { D.drawing = img; draw(); } };
  img.onerror = () => { if (D.name === name) $("drawing-status").textContent = `${name} could not be read as a picture`; };
  img.src = pictureUrl(name);
}
$("drawing-name").addEventListener("change", () => choose($("drawing-name").value));

// The workspace's pictures (other than the rest picture) to choose from.
on("files", (msg) => {
  if (!D.listing) return;
  D.listing = false;
  const select = $("drawing-name");
  const rest = S.state && S.state.texture_name;
  const names = msg.files.filter((f) => f.kind === "picture" && f.name !== rest).map((f) => f.name);
  select.textContent = "";
  const none = document.createElement("option");
  none.value = "";
  none.textContent = names.length ? "choose…" : "no other pictures: add one from disk";
  select.appendChild(none);
  for (const n of names) {
    const o = document.createElement("option");
    o.value = n; o.textContent = n;
    select.appendChild(o);
  }
  const want = msg.stored && names.includes(msg.stored) ? msg.stored : names.includes(D.name) ? D.name : "";
  select.value = want;
  if (want !== D.name || !D.drawing) choose(want);
  else draw();
});

export function openDrawing() {
  if (!S.state) return;
  if (!S.state.textured) {
    S.errors.push("open a picture of the subject first: drawings are laid over its mesh");
    redraw();
    return;
  }
  D.listing = true;
  S.filesFor = "drawing";
  send({ op: "list_files" });
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  $("drawing-time").placeholder = String(+(last + 1).toFixed(2));
  draw();
  if (!$("drawing-dialog").open) $("drawing-dialog").showModal();
}
$("drawing-open").onclick = openDrawing;
$("drawing-close").onclick = () => $("drawing-dialog").close();
$("drawing-clear").onclick = () => { D.pairs = []; D.pending = null; changed(); };
$("drawing-upload").onclick = () => $("drawing-file").click();
$("drawing-file").addEventListener("change", async () => {
  const file = $("drawing-file").files[0];
  if (!file) return;
  // The studio answers with the workspace's files, naming the one stored.
  D.listing = true;
  S.filesFor = "drawing";
  upload(file.name, await file.arrayBuffer(), "store");
  $("drawing-file").value = "";
});
$("drawing-make").onclick = () => {
  if (!D.name) return;
  const request = { op: "drawing_keyframe", name: D.name, pairs: D.pairs.map((p) => [p.a, p.b]) };
  const t = $("drawing-time").value;
  if (t !== "") request.time = Number(t);
  if (send(request)) $("drawing-dialog").close();
};
// Escape while a pair is half placed drops that point only.
$("drawing-dialog").addEventListener("cancel", (e) => {
  if (D.pending) { e.preventDefault(); D.pending = null; draw(); }
});
on("state", () => { if ($("drawing-dialog").open) draw(); });
