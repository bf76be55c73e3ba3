// The editor's layout: the mode tabs (Outline, Pose, Animate), the tools of the current mode
// only, the side panel's sections for it, and the light or dark theme. The server knows two
// modes (outline and pose); Animate is posing with the keyframe tools shown, a choice of this
// page.

import { S, $, redraw } from "./view.js";
import { send } from "./net.js";
import { outlineMode } from "./outline.js";

S.ui = localStorage.getItem("bdmorph-ui") === "animate" ? "animate" : "pose";

export function setMode(ui) {
  if (ui === "outline") { outlineMode(); return; }
  S.ui = ui;
  localStorage.setItem("bdmorph-ui", ui);
  if (S.state && S.state.mode !== "pose") send({ op: "mode", mode: "pose" });
  syncLayout();
}

export function syncLayout() {
  const st = S.state;
  const mode = st && st.mode === "outline" ? "outline" : S.ui;
  $("outline-tools").hidden = mode !== "outline";
  $("pose-tools").hidden = mode !== "pose";
  $("animate-tools").hidden = mode !== "animate";
  for (const m of ["outline", "pose", "animate"]) {
    $(`${m}-mode`).classList.toggle("on", m === mode);
    $(`${m}-mode`).setAttribute("aria-selected", String(m === mode));
  }
  for (const id of ["key-panel", "pin-panel", "onion-panel"]) $(id).hidden = mode === "outline";
  document.body.dataset.mode = mode;
  const help = HELP[mode];
  if ($("help").textContent !== help) $("help").textContent = help;
}

// The line of help over the canvas, for the mode shown.
const HELP = {
  outline: "Drag a point to move it; click a segment to add one; right-click a point to remove it; New loop, then clicks, draws one. Wheel: zoom; middle button or Alt+drag: pan. ? lists every shortcut.",
  pose: "Click a vertex to pin it and drag it; drag a pin to move it (Shift+click: pin without dragging or select); drag off the mesh to select pins; right-click a pin to remove it. ? lists every shortcut.",
  animate: "Click or drag the timeline to scrub; drag a key to retime it (Alt: the later keys too); I inserts a key at the playhead; O shows onion skins. ? lists every shortcut.",
};

$("pose-mode").onclick = () => setMode("pose");
$("animate-mode").onclick = () => setMode("animate");

// The theme: the system's until chosen here.
export function setTheme(theme) {
  S.theme = theme;
  document.body.classList.toggle("dark", theme === "dark");
  localStorage.setItem("bdmorph-theme", theme);
  redraw();
}
export function toggleTheme() { setTheme(S.theme === "dark" ? "light" : "dark"); }
const savedTheme = localStorage.getItem("bdmorph-theme");
setTheme(savedTheme || (window.matchMedia && matchMedia("(prefers-color-scheme: dark)").matches ? "dark" : "light"));
$("theme").onclick = toggleTheme;
