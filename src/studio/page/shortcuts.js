// Keyboard shortcuts: one table, from which both the key handler and the help overlay (?) are
// made, so the overlay lists exactly what the keys do. Keys typed into a text or number field
// are the field's; on the canvas, buttons, checkboxes and the timeline they are the studio's.

import { S, $, fit, redraw } from "./view.js";
import { send } from "./net.js";
import { save } from "./files.js";
import { togglePlay, stepFrame, stepKey, insertKey, copyKey, pasteKey, duplicateKey, deleteKey, setLoop, zoomIn, zoomOut, zoomFit } from "./timeline.js";
import { setTool, selectAllPins, selectNone } from "./pose.js";
import { toggleOnion } from "./onion.js";
import { setMode, toggleTheme } from "./layout.js";
import { deleteSelectedLoop } from "./outline.js";

const plain = (key) => (e) => !e.ctrlKey && !e.metaKey && !e.altKey && e.key === key;
const ctrl = (key, shift = false) => (e) => (e.ctrlKey || e.metaKey) && e.shiftKey === shift && e.key.toLowerCase() === key;

// [id, keys as shown, what it does, test, action]
export const SHORTCUTS = [
  ["play", "Space", "Play or pause", plain(" "), togglePlay],
  ["frame-next", "→", "Next frame", plain("ArrowRight"), () => stepFrame(1)],
  ["frame-previous", "←", "Previous frame", plain("ArrowLeft"), () => stepFrame(-1)],
  ["key-next", "↑", "Next keyframe", plain("ArrowUp"), () => stepKey(1)],
  ["key-previous", "↓", "Previous keyframe", plain("ArrowDown"), () => stepKey(-1)],
  ["key-first", "Home", "First keyframe", plain("Home"), () => stepKey(-Infinity)],
  ["key-last", "End", "Last keyframe", plain("End"), () => stepKey(Infinity)],
  ["insert", "I", "Insert a keyframe at the playhead (the frame shown there)", (e) => plain("i")(e) || plain("I")(e), insertKey],
  ["copy", "Ctrl+C", "Copy the selected keyframe", ctrl("c"), copyKey],
  ["paste", "Ctrl+V", "Paste the copied keyframe at the playhead", ctrl("v"), pasteKey],
  ["duplicate", "Ctrl+D", "Duplicate the selected keyframe (after the last)", ctrl("d"), duplicateKey],
  ["delete", "Delete", "Delete the selected keyframe, or in Outline the loop selected with Shift+click (Undo brings it back)", (e) => plain("Delete")(e) || plain("Backspace")(e), () => { if (!deleteSelectedLoop()) deleteKey(false); }],
  ["undo", "Ctrl+Z", "Undo", ctrl("z"), () => send({ op: "undo" })],
  ["redo", "Ctrl+Shift+Z", "Redo (also Ctrl+Y)", (e) => ctrl("z", true)(e) || ctrl("y")(e), () => send({ op: "redo" })],
  ["save", "Ctrl+S", "Save", ctrl("s"), save],
  ["mode-outline", "1", "Outline mode", plain("1"), () => setMode("outline")],
  ["mode-pose", "2", "Pose mode", plain("2"), () => setMode("pose")],
  ["mode-animate", "3", "Animate mode", plain("3"), () => setMode("animate")],
  ["tool-drag", "D", "Drag tool: pin and pose", (e) => plain("d")(e), () => setTool("drag")],
  ["tool-pins", "P", "Pins tool: place pins, the mesh stays", (e) => plain("p")(e), () => setTool("pins")],
  ["tool-joints", "J", "Joints tool: add (click where two parts overlap), move (drag) or remove (right-click) a joint", (e) => plain("j")(e), () => setTool("joints")],
  ["select-all", "Ctrl+A", "Select every pin", ctrl("a"), selectAllPins],
  ["select-none", "Esc", "Select no pin (in Outline: close the loop drawn)", plain("Escape"), () => {
    if (S.state && S.state.drawing !== null && S.state.drawing !== undefined) send({ op: "outline_close" });
    else selectNone();
  }],
  ["onion", "O", "Onion skins on or off", (e) => plain("o")(e), toggleOnion],
  ["loop-from", "[", "Loop range from the playhead", plain("["), () => setLoop("from")],
  ["loop-to", "]", "Loop range to the playhead", plain("]"), () => setLoop("to")],
  ["zoom-in", "=", "Zoom the timeline in", (e) => plain("=")(e) || plain("+")(e), zoomIn],
  ["zoom-out", "-", "Zoom the timeline out", plain("-"), zoomOut],
  ["zoom-fit", "0", "The whole animation on the timeline", plain("0"), zoomFit],
  ["fit", "F", "Fit the view to the mesh", (e) => plain("f")(e), fit],
  ["theme", "T", "Light or dark", (e) => plain("t")(e), toggleTheme],
  ["help", "?", "This list", plain("?"), () => showHelp()],
];

export function showHelp() {
  const table = $("shortcut-list");
  if (!table.rows.length) {
    for (const [id, keys, what] of SHORTCUTS) {
      const row = table.insertRow();
      row.dataset.id = id;
      const k = row.insertCell(), w = row.insertCell();
      const kbd = document.createElement("kbd");
      kbd.textContent = keys;
      k.appendChild(kbd);
      w.textContent = what;
    }
  }
  if (!$("help-dialog").open) $("help-dialog").showModal();
}
$("help-button").onclick = showHelp;
$("help-close").onclick = () => $("help-dialog").close();

window.addEventListener("keydown", (e) => {
  const t = e.target;
  const typing = (t instanceof HTMLInputElement && !["range", "checkbox", "button", "submit"].includes(t.type)) || t instanceof HTMLSelectElement || t instanceof HTMLTextAreaElement;
  // Ctrl+S saves from anywhere, a field included.
  if (ctrl("s")(e)) { e.preventDefault(); save(); return; }
  if (typing || document.querySelector("dialog[open]")) return;
  for (const [, , , test, action] of SHORTCUTS) {
    if (test(e)) {
      e.preventDefault();
      action();
      redraw();
      return;
    }
  }
});
