// The timeline: keys on a bar (a click shows and poses a keyframe, a drag moves it in time,
// keyframes with flipped triangles marked), the time slider (the frame at that time, shared
// with every tab), playback at the project's frame rate (frames dropped, never slowed), and
// the keyframe commands.

import { S, $, nth, redraw, KIND_FRAME } from "./view.js";
import { send, request, on } from "./net.js";
import { confirmDialog } from "./panels.js";

export function sliderTime() {
  const st = S.state;
  return st ? (Number($("time").value) / 1000) * st.duration : 0;
}

function setSlider(time) {
  const st = S.state;
  $("time").value = String(Math.round((1000 * time) / Math.max(st.duration, 1e-9)));
  $("time-readout").textContent = `${time.toFixed(2)} s`;
}

export function drawTimeline() {
  const st = S.state, keys = $("keys");
  const duration = Math.max(st.duration, 1e-9);
  const posing = "keyframe" in st.shown;
  // The keys' elements are kept and updated in place: a click in progress never lands on one
  // that a redraw has just replaced.
  while (keys.children.length > st.keyframes.length) keys.lastChild.remove();
  while (keys.children.length < st.keyframes.length) {
    const el = document.createElement("div");
    el.onmousedown = (e) => {
      if (e.button !== 0) return;
      e.preventDefault();
      S.keyDrag = { index: Number(el.dataset.index), startX: e.clientX, moved: false };
    };
    keys.appendChild(el);
  }
  st.keyframes.forEach((k, i) => {
    const el = keys.children[i];
    const className = "key" + (i === st.current && posing ? " current" : "") + (k.flipped ? " flipped" : "");
    if (el.className !== className) el.className = className;
    const left = `${(100 * k.time) / duration}%`;
    if (el.style.left !== left && !(S.keyDrag && S.keyDrag.index === i && S.keyDrag.moved)) el.style.left = left;
    el.title = `keyframe ${nth(i)} at ${k.time} s (${k.easing})` + (k.flipped ? `: ${k.flipped} flipped triangles (Repair fixes them)` : "");
    el.dataset.index = String(i);
    const text = k.flipped ? "!" : "";
    if (el.textContent !== text) el.textContent = text;
  });
  // The fields follow the keyframe shown (never another's).
  const key = st.keyframes[st.current];
  if (document.activeElement !== $("key-time") || S.keyFieldFor !== st.current) $("key-time").value = key.time;
  S.keyFieldFor = st.current;
  $("key-time").disabled = st.current === 0;
  $("key-easing").value = [...$("key-easing").options].some((o) => o.value === key.easing) ? key.easing : "linear";
  if (document.activeElement !== $("fps")) $("fps").value = st.fps;
  $("delete-key").disabled = st.current === 0;
  if (!S.playing && !S.sliding && "time" in st.shown && S.showing === "frame") setSlider(S.frameInfo.time);
  if (!S.playing && !S.sliding && posing) setSlider(key.time);
}

// A key on the timeline: a click selects it, a drag moves it in time (between its neighbours).
function keyDragTime(clientX) {
  const st = S.state, k = S.keyDrag.index;
  const r = $("keys").getBoundingClientRect();
  const duration = Math.max(st.duration, 1e-9);
  let time = Math.max(0, ((clientX - r.left) / r.width) * duration);
  const after = st.keyframes[k - 1].time;
  const before = k + 1 < st.keyframes.length ? st.keyframes[k + 1].time : Infinity;
  const gap = 1e-3;
  time = Math.min(Math.max(time, after + gap), before - gap);
  return Math.round(time * 1000) / 1000;
}
window.addEventListener("mousemove", (e) => {
  if (!S.keyDrag || S.keyDrag.index === 0) return;
  if (Math.abs(e.clientX - S.keyDrag.startX) < 3 && !S.keyDrag.moved) return;
  S.keyDrag.moved = true;
  const el = $("keys").children[S.keyDrag.index];
  const time = keyDragTime(e.clientX);
  el.style.left = `${Math.min(100, (100 * time) / Math.max(S.state.duration, 1e-9))}%`;
  el.title = `${time} s`;
});
window.addEventListener("mouseup", (e) => {
  if (!S.keyDrag) return;
  const { index, moved } = S.keyDrag;
  S.keyDrag = null;
  if (moved) send({ op: "set_time", keyframe: index, time: keyDragTime(e.clientX) });
  send({ op: "select", keyframe: index });
});

// A frame shown (asked for here or in another tab): the slider follows its time.
on("frame", (kind) => {
  if (kind === KIND_FRAME && !S.playing && !S.sliding && S.state) setSlider(S.frameInfo.time);
});

$("time").addEventListener("input", () => {
  S.sliding = true;
  const time = sliderTime();
  $("time-readout").textContent = `${time.toFixed(2)} s`;
  request({ op: "scrub", time });
});
$("time").addEventListener("change", () => { S.sliding = false; });

// Playback: the time follows the clock; a frame is asked for at each step of 1/fps when the
// last one has come back (late frames are dropped, the clock is never slowed).
let clock = null;
function tick(now) {
  if (!S.playing) return;
  const st = S.state;
  const fps = Math.max(1, st.fps);
  let time = clock.from + (now - clock.start) / 1000;
  if (time > st.duration) {
    if ($("loop").checked) {
      clock = { start: now, from: 0 };
      time = 0;
    } else {
      time = st.duration;
      stop();
    }
  }
  const step = Math.floor(time * fps + 1e-9);
  if (step !== clock.step && !S.busy()) {
    clock.step = step;
    const at = Math.min(step / fps, st.duration);
    setSlider(at);
    request({ op: "scrub", time: at });
  }
  if (S.playing) requestAnimationFrame(tick);
}
function stop() {
  S.playing = false;
  $("play").textContent = "Play";
}
export function togglePlay() {
  const st = S.state;
  if (!st || st.keyframes.length < 2) { S.errors.push("add a second keyframe to play"); redraw(); return; }
  if (S.playing) { stop(); return; }
  S.playing = true;
  $("play").textContent = "Pause";
  const from = sliderTime() >= st.duration - 1e-9 ? 0 : sliderTime();
  clock = { start: performance.now(), from, step: -1 };
  requestAnimationFrame(tick);
}
$("play").onclick = togglePlay;

// A new keyframe one second after the last: a copy of the first ("add") or of the one shown
// ("clone").
function addKeyframe(copy) {
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  send({ op: "add_keyframe", time: Math.round((last + 1) * 1000) / 1000, copy });
}
$("add-key").onclick = () => addKeyframe(0);
$("clone-key").onclick = () => addKeyframe(S.state.current);
$("frame-key").onclick = () => send({ op: "frame_to_keyframe", time: sliderTime() });
$("delete-key").onclick = async () => {
  const k = S.state.current;
  if (k === 0) return;
  if (await confirmDialog(`Delete keyframe ${nth(k)}? (Undo brings it back.)`, "Delete")) {
    send({ op: "delete_keyframe", keyframe: k });
  }
};
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
  const last = S.state.keyframes[S.state.keyframes.length - 1].time;
  send({ op: "load_keyframe", name: file.name, text: await file.text(), time: Math.round((last + 1) * 1000) / 1000 });
  $("load-file").value = "";
});
$("fps").addEventListener("change", () => send({ op: "fps", fps: Number($("fps").value) }));
$("key-time").addEventListener("change", () => send({ op: "set_time", keyframe: S.state.current, time: Number($("key-time").value) }));
$("key-easing").addEventListener("change", () => send({ op: "set_easing", keyframe: S.state.current, easing: $("key-easing").value }));
