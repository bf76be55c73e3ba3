// The timeline: one time axis for the ruler (seconds and frames), the keys (with thumbnails of
// their poses) and the playhead. A click or drag on it scrubs; a drag on a key retimes it (Alt,
// or the ripple toggle, moves every later key with it); the wheel zooms the axis about the
// cursor and Shift+wheel scrolls it. Playback runs on the clock at the project's frame rate
// (late frames are dropped, the clock is never slowed), over the loop range when one is set.
// Keyframe commands: insert at the playhead (the frame shown there), copy and paste at the
// playhead, duplicate, delete, reorder, load.

import { S, $, nth, redraw, onDraw, dpr, KIND_FRAME } from "./view.js";
import { send, request, on, needPoses } from "./net.js";
import { confirmDialog } from "./panels.js";

const PAD = 26; // pixels of axis before 0 and after the end

// The visible span of the axis: [start, start + span] seconds (fitted to the animation until
// zoomed or scrolled).
S.axis = { start: 0, span: null };
S.localTime = 0;      // the playhead while playing or scrubbing here
S.copied = null;      // { keyframe, rev } of the copied keyframe

function span() {
  const st = S.state;
  return S.axis.span || Math.max(st ? st.timeline : 1, 0.5);
}
// The axis's size, kept by an observer: reading it from the element would force a layout of
// the page on every frame.
let box = { w: 1, h: 1, rw: 1, rh: 1 };
new ResizeObserver(() => {
  box = { w: $("time").clientWidth, h: $("time").clientHeight, rw: $("ruler").clientWidth, rh: $("ruler").clientHeight };
  if (S.state) drawTimeline();
}).observe($("time"));
function width() { return Math.max(1, box.w - 2 * PAD); }
export function timeToX(t) { return PAD + ((t - S.axis.start) / span()) * width(); }
export function xToTime(x) { return S.axis.start + ((x - PAD) / width()) * span(); }
// For scripted tests: the page position of a time on the axis.
S.timeToPage = (t) => {
  const r = $("time").getBoundingClientRect();
  return [r.left + 1 + timeToX(t), r.top + r.height / 2];
};

// The time the playhead shows: while playing, or while a time asked for here is not shown
// yet, that time (the frame for it is on its way: nothing can overtake it in the one-slot
// mailbox, and the server drops a scrub only for a newer one); otherwise the time of the
// frame shown, exactly as the server holds it. The readout, the status line, and every
// command at the playhead (insert, paste, loop ends, zoom) read it here, so they agree.
export function playheadTime() {
  if (!S.state) return 0;
  if (S.playing || S.sliding) return S.localTime;
  return S.frameInfo.time;
}
// A time asked for: the playhead shows it until the frame for it has come.
function showTime(time) {
  S.localTime = time;
  S.sliding = true;
  request({ op: "scrub", time });
}
// The frame asked for has come (nothing in flight or waiting) and no drag goes on: the
// playhead is the frame's again.
function settleSlide() {
  if (S.sliding && !S.scrubbing && !S.playing && !S.busy()) S.sliding = false;
}
// Kept for the exports' "still at the playhead".
export const sliderTime = playheadTime;

function setText(id, text) { const el = $(id); if (el.textContent !== text) el.textContent = text; }
function readout(time) {
  const fps = S.state ? S.state.fps : 25;
  setText("time-readout", `${time.toFixed(2)} s`);
  setText("frame-readout", `frame ${Math.round(time * fps)}`);
}

// The ruler: a tick per frame when there is room, seconds labelled at a readable step (drawn
// again only when the axis, the duration, the frame rate, the size or the theme change).
let rulerStamp = "";
function drawRuler() {
  const c = $("ruler"), st = S.state;
  const w = box.rw, h = box.rh;
  const stamp = [S.axis.start, span(), st.duration, st.timeline, st.fps, w, h, S.theme, dpr()].join();
  if (stamp === rulerStamp) return;
  rulerStamp = stamp;
  if (c.width !== Math.round(w * dpr())) { c.width = Math.round(w * dpr()); c.height = Math.round(h * dpr()); }
  const g = c.getContext("2d");
  g.setTransform(dpr(), 0, 0, dpr(), 0, 0);
  g.clearRect(0, 0, w, h);
  const css = getComputedStyle(document.body);
  g.strokeStyle = g.fillStyle = css.getPropertyValue("--ruler") || "#888";
  g.font = "10px system-ui";
  const pxPerSecond = width() / span();
  const fps = Math.max(1, st.fps);
  const t0 = Math.max(0, xToTime(0)), t1 = xToTime(w);
  // Frames: a small tick each when they are at least 5 px apart.
  if (pxPerSecond / fps >= 5) {
    g.beginPath();
    for (let f = Math.ceil(t0 * fps); f <= t1 * fps; f++) {
      const x = Math.round(timeToX(f / fps)) + 0.5;
      g.moveTo(x, h - 4); g.lineTo(x, h);
    }
    g.stroke();
  }
  // Seconds: the smallest step that leaves 70 px between labels.
  const steps = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 30, 60, 120, 300, 600];
  const step = steps.find((s) => s * pxPerSecond >= 70) || 600;
  g.beginPath();
  for (let i = Math.ceil(t0 / step); i * step <= t1; i++) {
    const t = i * step, x = Math.round(timeToX(t)) + 0.5;
    g.moveTo(x, h - 10); g.lineTo(x, h);
    const label = `${+t.toFixed(2)} s`;
    const frame = Math.round(t * fps);
    g.fillText(Math.abs(t * fps - frame) < 1e-6 ? `${label} · ${frame}` : label, x + 3, 10);
  }
  g.stroke();
  // Past the end of the animation (where playback and exports stop; the playhead may go on
  // to the end of the timeline, to make a keyframe there), and past the timeline.
  g.fillStyle = "rgba(128,128,128,0.18)";
  const end = timeToX(st.duration), last = timeToX(st.timeline);
  if (end < w) g.fillRect(end, 0, w - end, h);
  if (last < w) g.fillRect(last, 0, w - last, h);
}

// A thumbnail of keyframe k's pose (its boundary), all at one scale so motion shows.
let thumbBounds = null;
function poseBounds() {
  let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
  for (const { pos } of S.ghosts.values()) {
    for (let i = 0; i < pos.length; i += 2) {
      if (pos[i] < lo[0]) lo[0] = pos[i]; if (pos[i] > hi[0]) hi[0] = pos[i];
      if (pos[i + 1] < lo[1]) lo[1] = pos[i + 1]; if (pos[i + 1] > hi[1]) hi[1] = pos[i + 1];
    }
  }
  return lo[0] <= hi[0] ? { lo, hi } : null;
}
function drawThumb(canvas, k) {
  const ghost = S.ghosts.get(k);
  const w = 42, h = 30;
  if (canvas.width !== w * dpr()) { canvas.width = w * dpr(); canvas.height = h * dpr(); }
  const g = canvas.getContext("2d");
  g.setTransform(dpr(), 0, 0, dpr(), 0, 0);
  g.clearRect(0, 0, w, h);
  if (!ghost || !thumbBounds || !S.boundary.length) return;
  const { lo, hi } = thumbBounds;
  const s = Math.min((w - 6) / Math.max(hi[0] - lo[0], 1e-9), (h - 6) / Math.max(hi[1] - lo[1], 1e-9));
  const ox = w / 2 - (s * (lo[0] + hi[0])) / 2, oy = h / 2 + (s * (lo[1] + hi[1])) / 2;
  const P = ghost.pos;
  g.strokeStyle = getComputedStyle(document.body).getPropertyValue("--text") || "#222";
  g.lineWidth = 1;
  g.beginPath();
  for (const [a, b] of S.boundary) {
    g.moveTo(ox + s * P[2 * a], oy - s * P[2 * a + 1]);
    g.lineTo(ox + s * P[2 * b], oy - s * P[2 * b + 1]);
  }
  g.stroke();
}

export function drawTimeline() {
  const st = S.state, keys = $("keys");
  if (!st) return;
  const posing = "keyframe" in st.shown;
  // Every key's pose, for the thumbnails (at most 64 asked for at a time; none for very large
  // animations, whose thumbnails would hold too much memory in the page).
  if (S.n * st.keyframes.length <= 4e6) needPoses(st.keyframes.map((_, i) => i).slice(0, 64));
  // The keys' elements are kept and updated in place: a click in progress never lands on one
  // that a redraw has just replaced.
  while (keys.children.length > st.keyframes.length) keys.lastChild.remove();
  while (keys.children.length < st.keyframes.length) {
    const el = document.createElement("div");
    el.append(document.createElement("canvas"), document.createElement("div"));
    el.lastChild.className = "mark";
    el.onmousedown = (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      e.stopPropagation();
      const index = Number(el.dataset.index);
      S.keyDrag = {
        index, startX: e.clientX, moved: false,
        ripple: e.altKey || $("ripple").checked,
        times: S.state.keyframes.map((k) => k.time),
      };
    };
    keys.appendChild(el);
  }
  thumbBounds = poseBounds();
  st.keyframes.forEach((k, i) => {
    const el = keys.children[i];
    const className = "key" + (i === st.current && posing ? " current" : "") + (k.flipped ? " flipped" : "")
      + (S.copied && S.copied.rev === k.rev ? " copied" : "");
    if (el.className !== className) el.className = className;
    const dragging = S.keyDrag && S.keyDrag.moved && (S.keyDrag.index === i || (S.keyDrag.ripple && i > S.keyDrag.index));
    const left = `${timeToX(k.time)}px`;
    if (el.style.left !== left && !dragging) el.style.left = left;
    el.title = `keyframe ${nth(i)} at ${k.time} s (${k.easing})` + (k.flipped ? `: ${k.flipped} flipped triangles (Repair fixes them)` : "");
    el.dataset.index = String(i);
    const text = k.flipped ? "!" : "";
    if (el.lastChild.textContent !== text) el.lastChild.textContent = text;
    const ghost = S.ghosts.get(i);
    const stamp = `${ghost ? ghost.rev : -1}:${thumbBounds ? thumbBounds.lo.concat(thumbBounds.hi).join() : ""}:${S.theme}`;
    if (el.dataset.stamp !== stamp) { el.dataset.stamp = stamp; drawThumb(el.firstChild, i); }
  });
  // The fields follow the keyframe shown (never another's).
  const key = st.keyframes[st.current];
  if (document.activeElement !== $("key-time") || S.keyFieldFor !== st.current) $("key-time").value = key.time;
  S.keyFieldFor = st.current;
  $("key-time").disabled = st.current === 0;
  if (document.activeElement !== $("fps")) $("fps").value = st.fps;
  if (document.activeElement !== $("scene-length")) {
    $("scene-length").value = st.length === null || st.length === undefined ? "" : st.length;
    $("scene-length").placeholder = `${+st.duration.toFixed(2)}`;
  }
  $("delete-key").disabled = st.current === 0;
  $("paste-key").disabled = !S.copied;
  drawPlayhead();
}

function drawPlayhead() {
  const st = S.state;
  if (!st) return;
  const t = playheadTime();
  const left = `${timeToX(t)}px`;
  if ($("playhead").style.left !== left) $("playhead").style.left = left;
  readout(t);
  const range = st.loop_range, shade = $("loop-range");
  if (shade.hidden !== !range) shade.hidden = !range;
  if (range) {
    shade.style.left = `${timeToX(range[0])}px`;
    shade.style.width = `${Math.max(0, timeToX(range[1]) - timeToX(range[0]))}px`;
  }
  drawRuler();
}
// Each redraw moves the playhead; the keys are laid out again only when the state, the poses
// received, the theme or the axis changed.
let keysFor = [];
onDraw(() => {
  if (!S.state) return;
  settleSlide();
  const now = [S.state, S.ghostVersion, S.theme, S.axis.start, S.axis.span, S.copied];
  if (now.some((x, i) => x !== keysFor[i])) { keysFor = now; drawTimeline(); }
  drawPlayhead();
});

// A key dragged: its time (and with ripple the later keys' times, by the same shift).
function keyDragTime(clientX) {
  const st = S.state, d = S.keyDrag, k = d.index;
  const r = $("time").getBoundingClientRect();
  let time = Math.max(0, xToTime(clientX - r.left - 1));
  const after = d.times[k - 1];
  const before = !d.ripple && k + 1 < d.times.length ? d.times[k + 1] : Infinity;
  const gap = 1e-3;
  time = Math.min(Math.max(time, after + gap), before - gap);
  // Snapped to whole frames when the frames are far enough apart to aim at.
  const fps = Math.max(1, st.fps);
  const snapped = Math.round(time * fps) / fps;
  if (width() / span() / fps >= 6 && snapped > after + gap && snapped < before - gap) time = snapped;
  return Math.round(time * 1000) / 1000;
}
window.addEventListener("mousemove", (e) => {
  if (S.scrubbing) { scrubAt(e.clientX); return; }
  const d = S.keyDrag;
  if (!d || d.index === 0) return;
  if (Math.abs(e.clientX - d.startX) < 3 && !d.moved) return;
  d.moved = true;
  const time = keyDragTime(e.clientX);
  const shift = time - d.times[d.index];
  const keys = $("keys").children;
  keys[d.index].style.left = `${timeToX(time)}px`;
  keys[d.index].title = `${time} s`;
  if (d.ripple) for (let i = d.index + 1; i < keys.length; i++) keys[i].style.left = `${timeToX(d.times[i] + shift)}px`;
});
window.addEventListener("mouseup", (e) => {
  if (S.scrubbing) { S.scrubbing = false; settleSlide(); return; }
  if (!S.keyDrag) return;
  const { index, moved, ripple } = S.keyDrag;
  const time = moved ? keyDragTime(e.clientX) : 0;
  S.keyDrag = null;
  if (moved) send({ op: "set_time", keyframe: index, time, ripple });
  send({ op: "select", keyframe: index });
});

// Scrubbing: a click or drag on the axis shows the frame there (a key's own time within 5 px
// of it, so a click near a key shows that keyframe).
function scrubAt(clientX) {
  const st = S.state;
  const r = $("time").getBoundingClientRect();
  const x = clientX - r.left - 1;
  let time = Math.min(Math.max(xToTime(x), 0), st.timeline);
  for (const k of st.keyframes) if (Math.abs(timeToX(k.time) - x) <= 5) time = k.time;
  showTime(time);
  readout(time);
  drawPlayhead();
}
$("time").addEventListener("mousedown", (e) => {
  if (e.button !== 0 || !S.state) return;
  e.preventDefault();
  if (S.playing) stop();
  S.scrubbing = true;
  S.sliding = true;
  scrubAt(e.clientX);
});

// A frame shown (asked for here or in another tab): the playhead follows.
on("frame", (kind) => { settleSlide(); if (kind === KIND_FRAME && !S.playing && !S.sliding) redraw(); });

// Zoom (wheel) about the cursor and scroll (Shift+wheel, or a sideways wheel).
function zoomAxis(factor, aboutX) {
  const st = S.state;
  if (!st) return;
  const t = xToTime(aboutX);
  const fps = Math.max(1, st.fps);
  const s = Math.min(Math.max(span() * factor, Math.max(4 / fps, 0.02)), Math.max(st.timeline, 1) * 4);
  S.axis.span = s;
  S.axis.start = t - ((aboutX - PAD) / width()) * s;
  clampAxis();
  drawTimeline();
}
function clampAxis() {
  const st = S.state, s = span();
  S.axis.start = Math.min(Math.max(S.axis.start, -0.02 * s), Math.max(0, st.timeline - 0.1 * s));
}
function scrollAxis(dx) {
  S.axis.start += (dx / width()) * span();
  clampAxis();
  drawTimeline();
}
export function zoomIn() { zoomAxis(1 / 1.5, timeToX(playheadTime())); }
export function zoomOut() { zoomAxis(1.5, timeToX(playheadTime())); }
export function zoomFit() { S.axis = { start: 0, span: null }; drawTimeline(); }
$("time").addEventListener("wheel", (e) => {
  e.preventDefault();
  const r = $("time").getBoundingClientRect();
  if (e.shiftKey || Math.abs(e.deltaX) > Math.abs(e.deltaY)) scrollAxis(e.shiftKey ? e.deltaY : e.deltaX);
  else zoomAxis(Math.exp(e.deltaY * 0.002), e.clientX - r.left - 1);
}, { passive: false });
$("zoom-in").onclick = zoomIn;
$("zoom-out").onclick = zoomOut;
$("zoom-fit").onclick = zoomFit;

// Playback: the time follows the clock; a frame is asked for at each step of 1/fps when the
// last one has come back (late frames are dropped, the clock is never slowed).
let clock = null;
function range() {
  const st = S.state, r = st.loop_range;
  if (!r || !$("loop").checked) return { from: 0, to: st.duration };
  const to = Math.min(r[1], st.duration);
  return to > r[0] ? { from: r[0], to } : { from: 0, to: st.duration };
}
function tick(now) {
  if (!S.playing) return;
  const st = S.state;
  const fps = Math.max(1, st.fps);
  const { from, to } = range();
  let time = clock.from + (now - clock.start) / 1000;
  if (time > to) {
    if ($("loop").checked) {
      clock = { start: now, from, step: -1 };
      time = from;
    } else {
      // The end is shown (asked for even when a frame is still on its way).
      stop();
      showTime(to);
      redraw();
      return;
    }
  }
  S.localTime = time;
  const step = Math.floor(time * fps + 1e-9);
  if (step !== clock.step && !S.busy()) {
    clock.step = step;
    const at = Math.min(Math.max(step / fps, from), to);
    clock.at = at;
    readout(at);
    drawPlayhead();
    request({ op: "scrub", time: at });
  }
  if (S.playing) requestAnimationFrame(tick);
}
function stop() {
  S.playing = false;
  // The playhead stays on the last frame asked for until it is shown, then is that frame's.
  if (clock && clock.at !== undefined) { S.localTime = clock.at; S.sliding = true; }
  $("play").textContent = "Play";
  redraw();
}
export function togglePlay() {
  const st = S.state;
  if (!st || st.keyframes.length < 2) { S.errors.push("add a second keyframe to play"); redraw(); return; }
  if (S.playing) { stop(); return; }
  const { from, to } = range();
  const now = playheadTime();
  const start = now >= to - 1e-9 || now < from ? from : now;
  S.playing = true;
  S.localTime = start;
  $("play").textContent = "Pause";
  clock = { start: performance.now(), from: start, step: -1 };
  requestAnimationFrame(tick);
}
$("play").onclick = togglePlay;

// Stepping: a frame (Left/Right) or a keyframe (Up/Down, Home/End).
export function stepFrame(direction) {
  const st = S.state;
  if (!st) return;
  if (S.playing) stop();
  const fps = Math.max(1, st.fps);
  const frame = Math.round(playheadTime() * fps) + direction;
  const time = Math.min(Math.max(frame / fps, 0), st.timeline);
  showTime(time);
  redraw();
}
export function stepKey(direction) {
  const st = S.state;
  if (!st) return;
  if (S.playing) stop();
  const t = playheadTime(), times = st.keyframes.map((key) => key.time);
  let k;
  if (direction === Infinity) k = times.length - 1;
  else if (direction === -Infinity) k = 0;
  else if (direction > 0) k = times.findIndex((time) => time > t + 1e-9);
  else k = times.map((time) => time < t - 1e-9).lastIndexOf(true);
  if (k >= 0 && k < st.keyframes.length) send({ op: "select", keyframe: k });
}

// Keyframe commands.
function lastPlusOne() {
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  return Math.round((last + 1) * 1000) / 1000;
}
export function insertKey() {
  const st = S.state;
  if (!st) return;
  const t = playheadTime();
  const k = st.keyframes.findIndex((key) => Math.abs(key.time - t) < 1e-6);
  if (k >= 0) { S.errors.push(`keyframe ${nth(k)} is at the playhead already: move the playhead between keys or past the last to insert one`); redraw(); return; }
  send({ op: "frame_to_keyframe", time: t });
}
export function copyKey() {
  const st = S.state;
  if (!st) return;
  S.copied = { keyframe: st.current, rev: st.keyframes[st.current].rev };
  S.flash = { text: `keyframe ${nth(st.current)} copied`, until: performance.now() + 2500 };
  drawTimeline();
  redraw();
}
export function pasteKey() {
  const st = S.state;
  if (!st || !S.copied) return;
  // The copied keyframe by its pose's revision: found again if keyframes moved since.
  const k = st.keyframes.findIndex((key) => key.rev === S.copied.rev);
  if (k < 0) { S.errors.push("the copied keyframe was changed or deleted since: copy it again"); redraw(); return; }
  const t = Math.round(playheadTime() * 1000) / 1000;
  const clash = st.keyframes.findIndex((key) => Math.abs(key.time - t) < 1e-6);
  if (clash < 0) { send({ op: "add_keyframe", time: t, copy: k }); return; }
  // Onto a keyframe: replace its pose, or insert the copy a frame after it (halfway to the
  // next keyframe when that is nearer). Asked, never decided silently.
  const next = st.keyframes[clash + 1];
  let after = Math.round((st.keyframes[clash].time + 1 / Math.max(1, st.fps)) * 1000) / 1000;
  if (next && after >= next.time - 1e-6) after = Math.round(((st.keyframes[clash].time + next.time) / 2) * 1000) / 1000;
  const insert = `Insert after (${after.toFixed(2)} s)`;
  const text = clash === k
    ? `The copied keyframe ${nth(k)} is at the playhead: insert its copy after it, at ${after} s?`
    : `Keyframe ${nth(clash)} is at the playhead (${t} s). Replace its pose and pins with keyframe ${nth(k)}'s, or insert the copy after it, at ${after} s?`;
  const asked = clash === k ? confirmDialog(text, insert) : confirmDialog(text, "Replace", insert);
  asked.then((choice) => {
    if (choice === true && clash !== k) send({ op: "replace_keyframe", keyframe: clash, copy: k });
    else if (choice === "other" || (choice === true && clash === k)) send({ op: "add_keyframe", time: after, copy: k });
  });
}
export function duplicateKey() { if (S.state) send({ op: "add_keyframe", time: lastPlusOne(), copy: S.state.current }); }
export function deleteKey(ask = true) {
  const k = S.state.current;
  if (k === 0) { S.errors.push("the first keyframe is the animation's start: it cannot be deleted"); redraw(); return; }
  const go = () => send({ op: "delete_keyframe", keyframe: k });
  if (!ask) { go(); return; }
  confirmDialog(`Delete keyframe ${nth(k)}? (Undo brings it back.)`, "Delete").then((yes) => { if (yes) go(); });
}
export function setLoop(which) {
  const st = S.state;
  if (!st) return;
  const t = Math.round(playheadTime() * 1000) / 1000;
  const [from, to] = st.loop_range || [0, st.duration];
  let range = null;
  if (which === "from") range = t < to ? [t, to] : [t, Math.max(st.duration, t + 1 / st.fps)];
  else if (which === "to") range = t > from ? [from, t] : [0, t];
  if (range && !(range[1] > range[0])) { S.errors.push("the loop range needs some time between its ends"); redraw(); return; }
  send({ op: "loop_range", range });
}

$("add-key").onclick = () => send({ op: "add_keyframe", time: lastPlusOne(), copy: 0 });
$("clone-key").onclick = duplicateKey;
$("duplicate-key").onclick = duplicateKey;
$("frame-key").onclick = insertKey;
$("insert-key").onclick = insertKey;
$("copy-key").onclick = copyKey;
$("paste-key").onclick = pasteKey;
$("delete-key").onclick = () => deleteKey(true);
$("loop-in").onclick = () => setLoop("from");
$("loop-out").onclick = () => setLoop("to");
$("loop-clear").onclick = () => setLoop(null);
$("key-earlier").onclick = () => {
  const k = S.state.current;
  if (k > 0) send({ op: "move_keyframe", keyframe: k, to: k - 1 });
};
$("key-later").onclick = () => {
  const k = S.state.current;
  if (k + 1 < S.state.keyframes.length) send({ op: "move_keyframe", keyframe: k, to: k + 1 });
};
$("load-key").onclick = () => $("load-file").click();
$("load-file").addEventListener("change", async () => {
  const file = $("load-file").files[0];
  if (!file) return;
  send({ op: "load_keyframe", name: file.name, text: await file.text(), time: lastPlusOne() });
  $("load-file").value = "";
});
$("fps").addEventListener("change", () => send({ op: "fps", fps: Number($("fps").value) }));
// The scene's length (empty: it ends at the last keyframe).
$("scene-length").addEventListener("change", () => {
  const text = $("scene-length").value.trim();
  const length = text === "" ? null : Number(text);
  if (length === S.state.length || (length === null && S.state.length == null)) return;
  send({ op: "length", length });
});
$("key-time").addEventListener("change", () => send({ op: "set_time", keyframe: S.state.current, time: Number($("key-time").value) }));
