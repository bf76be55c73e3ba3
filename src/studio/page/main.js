// bdmorph studio: the page. Plain JavaScript modules; the document and the engine are on the
// server, reached over one WebSocket (net.js). Every panel draws what the server last said.

import { S, $, fit, resize, redraw } from "./view.js";
import { connect, on, textureUrl } from "./net.js";
import { GL } from "./gl.js";
import { computePieces } from "./overlay.js";
import { syncMethod } from "./pose.js";
import { syncOutlineTools } from "./outline.js";
import { drawTimeline } from "./timeline.js";
import { connection } from "./panels.js";
import { syncLayout } from "./layout.js";
import { drawKeyPanel } from "./easing.js";
import "./shortcuts.js";
import { setPaint } from "./paint.js";
import { drawPartsPanel } from "./parts.js";
import "./looks.js";
import "./drawing.js";

on("paint", ({ depth, stiffness }) => {
  setPaint(depth, stiffness);
  GL.setMesh();
});

let firstMesh = true;
on("mesh", () => {
  GL.setMesh();
  computePieces();
  if (S.texture && S.uv) GL.setTexture(S.texture);
  $("pieces").checked = S.pieceCount > 1 || $("pieces").checked;
  // The view is fitted to a new mesh, not to every message about the same one.
  const bounds = `${S.n}:${S.m}:${S.rest[0]}:${S.rest[1]}`;
  if (firstMesh || S.meshKey !== bounds) fit();
  S.meshKey = bounds;
  firstMesh = false;
});

function loadTexture(rev) {
  S.textureRev = rev;
  const img = new Image();
  img.onload = () => {
    if (S.textureRev !== rev) return;
    S.texture = img;
    GL.setTexture(img);
    redraw();
  };
  img.onerror = () => { if (S.textureRev === rev) { S.texture = null; GL.setTexture(null); } };
  img.src = textureUrl(rev);
}

let everTextured = false;
on("state", (st) => {
  if (st.texture_name && st.texture_rev !== S.textureRev) loadTexture(st.texture_rev);
  if (!st.texture_name && S.texture) { S.texture = null; S.textureRev = -1; GL.setTexture(null); }
  // A picture's project opens showing the picture.
  if (st.textured && !everTextured) $("texture").checked = true;
  everTextured = everTextured || st.textured;
  syncMethod();
  syncOutlineTools();
  syncLayout();
  drawTimeline();
  drawKeyPanel();
  drawPartsPanel();
});

on("error", (msg) => {
  if (msg.handled) return;
  // Nothing to undo or redo is said in passing, not kept.
  if (/^nothing to (undo|redo)$/.test(msg.message)) {
    S.flash = { text: msg.message, until: performance.now() + 2500 };
    setTimeout(redraw, 2600);
    return;
  }
  S.errors.push(msg.message);
  // Equal errors are shown once with how many (panels.js): room for a few kinds.
  if (S.errors.length > 50) S.errors.shift();
});
on("open", () => connection(true));
on("close", (was) => connection(false, was));

for (const id of ["edges", "colours", "texture", "overlay", "anchor", "pieces", "highlight"]) $(id).addEventListener("change", redraw);
$("fit").onclick = fit;

// The canvas follows its element's size, whatever changed it (the window, or panels whose
// content changes the room left for it): a backing store of another size would be stretched,
// and the mouse would miss what is drawn.
new ResizeObserver(resize).observe($("view"));
resize();
connect();
