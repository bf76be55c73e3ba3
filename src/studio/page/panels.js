// The page's messages and small dialogs: the status bar (one line, fixed height), notes from
// the server and this page's refused requests (a note fades after a few seconds, an error
// stays until dismissed; equal ones are shown once, with how many), the progress of
// background work with Cancel, the connection banner, the undo and redo buttons with what
// they would do, and confirm/prompt dialogs.

import { S, $, nth, redraw, onDraw } from "./view.js";
import { send } from "./net.js";

export function showStatus() {
  const st = S.state;
  if (!st) return;
  const what = S.showing === "frame"
    ? `frame at ${S.frameInfo.time.toFixed(2)} s`
    : `keyframe ${nth(st.current)} of ${st.keyframes.length}`;
  const worst = Number.isFinite(S.frameInfo.worst) ? S.frameInfo.worst.toFixed(3) : "∞";
  const lat = S.stats.latencies.slice(-30);
  const mean = lat.length ? (lat.reduce((a, b) => a + b, 0) / lat.length).toFixed(1) : "–";
  const pieces = st.pieces > 1 ? ` · ${st.pieces} pieces (unpinned ones stay in place)` : "";
  const flips = S.frameInfo.flipped ? `, ${S.frameInfo.flipped} flipped` : ", none flipped";
  const pins = S.showing === "pose" ? ` · ${S.pins.length} pins` : "";
  const flash = S.flash && performance.now() < S.flash.until ? `${S.flash.text} · ` : "";
  $("status").textContent = `${flash}${what} · ${st.vertices} vertices, ${st.faces} triangles${pieces} · largest distortion ${worst}${flips}${pins} · ${mean} ms per update`;
  $("status").title = $("status").textContent;
}

// Notes from the server (for every tab) and this page's errors, newest last, each with ×.
// A note fades NOTE_MS after this page first showed it; an error stays until dismissed.
// Equal notes (the same text, both notes or both errors) are one, with "×N".
// (The fade itself is the last eighth of that time: studio.css, note-fade.)
export const NOTE_MS = 6000;
const noteSeen = new Map(); // server note id -> when this page first showed it
let noteTimer = null;
function drawNotes() {
  const box = $("notes");
  const st = S.state;
  const now = performance.now();
  const items = [];
  if (st) {
    const ids = new Set(st.notes.map((n) => n.id));
    for (const id of noteSeen.keys()) if (!ids.has(id)) noteSeen.delete(id);
    for (const n of st.notes) {
      if (!noteSeen.has(n.id)) noteSeen.set(n.id, now);
      items.push({ text: n.text, error: n.error, seen: noteSeen.get(n.id), dismiss: () => send({ op: "dismiss", note: n.id }) });
    }
  }
  S.errors.forEach((text) => items.push({ text, error: true, seen: now, dismiss: () => { S.errors = S.errors.filter((e) => e !== text); redraw(); } }));
  // Equal ones merged (at the place of the newest), then the faded ones left out.
  const groups = new Map();
  for (const item of items) {
    const k = JSON.stringify([item.text, item.error]);
    const g = groups.get(k);
    if (g) {
      groups.delete(k);
      g.count++;
      g.seen = Math.max(g.seen, item.seen);
      const first = g.dismiss, then = item.dismiss;
      g.dismiss = () => { first(); then(); };
      groups.set(k, g);
    } else groups.set(k, { ...item, count: 1 });
  }
  const shown = [...groups.values()].filter((g) => g.error || now - g.seen < NOTE_MS).slice(-6);
  // Drawn again when the next one fades.
  const next = Math.min(...shown.filter((g) => !g.error).map((g) => g.seen + NOTE_MS - now));
  clearTimeout(noteTimer);
  if (Number.isFinite(next)) noteTimer = setTimeout(redraw, Math.max(0, next) + 20);
  const key = JSON.stringify(shown.map((g) => [g.text, g.error, g.count, g.error ? 0 : g.seen]));
  if (box.dataset.key === key) return;
  box.dataset.key = key;
  box.textContent = "";
  for (const item of shown) {
    const el = document.createElement("div");
    el.className = "note" + (item.error ? " error" : " fades");
    // The fade runs over the note's time, wherever this drawing starts in it.
    if (!item.error) {
      el.style.animationDuration = `${NOTE_MS}ms`;
      el.style.animationDelay = `${-(now - item.seen)}ms`;
    }
    const text = document.createElement("span");
    text.textContent = item.text;
    el.append(text);
    if (item.count > 1) {
      const count = document.createElement("span");
      count.className = "count";
      count.textContent = `×${item.count}`;
      count.title = `${item.count} times`;
      el.append(count);
    }
    const x = document.createElement("button");
    x.textContent = "×";
    x.title = "Dismiss";
    x.className = "dismiss";
    x.onclick = item.dismiss;
    el.append(x);
    box.appendChild(el);
  }
}
function drawJob() {
  const st = S.state, box = $("job");
  if (!st || !st.job) { box.hidden = true; return; }
  box.hidden = false;
  const { label, done, total } = st.job;
  $("job-label").textContent = total ? `${label}: ${done} of ${total}` : `${label}…`;
  const bar = $("job-bar");
  if (total) { bar.max = total; bar.value = done; } else bar.removeAttribute("value");
}

function drawHistory() {
  const st = S.state;
  if (!st) return;
  $("undo").disabled = !st.undo;
  $("redo").disabled = !st.redo;
  $("undo").title = st.undo ? `Undo ${st.undo} (Ctrl+Z)` : "Nothing to undo";
  $("redo").title = st.redo ? `Redo ${st.redo} (Ctrl+Shift+Z)` : "Nothing to redo";
  $("history-label").textContent = st.undo ? `last: ${st.undo}` : "";
  if (st.history.dropped) $("history-label").title = `the ${st.history.dropped} oldest steps were dropped to keep the history within its memory limit`;
  $("repair").hidden = !(st.keyframes[st.current].flipped > 0);
  $("repair").textContent = `Repair ${st.keyframes[st.current].flipped} flipped`;
  $("texture").disabled = !st.textured;
  $("pieces-label").hidden = st.pieces < 2 && !$("pieces").checked;
}

onDraw(() => { drawNotes(); drawJob(); drawHistory(); showStatus(); });

$("undo").onclick = () => send({ op: "undo" });
$("redo").onclick = () => send({ op: "redo" });
$("job-cancel").onclick = () => send({ op: "cancel" });

// The connection: when the studio stops, what to do, truthfully; the page tries again.
export function connection(open, wasOpen) {
  const banner = $("banner-connection");
  if (open) { banner.hidden = true; return; }
  banner.hidden = false;
  const ws = S.state ? S.state.workspace : "its folder";
  banner.textContent = wasOpen
    ? `The studio stopped. Nothing is lost: unsaved changes were kept in ${ws}. Start it again there (bdmorph studio …): this page reconnects by itself when it listens on port ${location.port} again; otherwise open the URL it prints. Trying every 2 s…`
    : `Cannot reach the studio on port ${location.port}. Start it (bdmorph studio …) and this page connects by itself; trying every 2 s…`;
}

// A modal question; resolves to true for the action, false otherwise.
export function confirmDialog(text, action = "OK", other = null) {
  return new Promise((resolve) => {
    const d = $("confirm-dialog");
    $("confirm-text").textContent = text;
    $("confirm-ok").textContent = action;
    $("confirm-other").hidden = !other;
    if (other) $("confirm-other").textContent = other;
    const done = (value) => { d.close(); resolve(value); };
    $("confirm-ok").onclick = () => done(true);
    $("confirm-other").onclick = () => done("other");
    $("confirm-cancel").onclick = () => done(false);
    d.oncancel = () => resolve(false);
    d.showModal();
  });
}

// A modal question for a name; resolves to it, or null.
export function promptDialog(text, value) {
  return new Promise((resolve) => {
    const d = $("prompt-dialog");
    $("prompt-text").textContent = text;
    $("prompt-value").value = value;
    const done = (v) => { d.close(); resolve(v); };
    $("prompt-ok").onclick = () => done($("prompt-value").value.trim() || null);
    $("prompt-cancel").onclick = () => done(null);
    $("prompt-value").onkeydown = (e) => { if (e.key === "Enter") { e.preventDefault(); done($("prompt-value").value.trim() || null); } };
    d.oncancel = () => resolve(null);
    d.showModal();
    $("prompt-value").select();
  });
}
