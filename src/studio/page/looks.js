// Keyframes' own pictures: a keyframe made from a drawing is drawn with its drawing (its
// picture and texture coordinates, fetched once per revision), and between two keyframes of
// different pictures the frame cross-fades them as exports do: smoothly along the segment's
// eased time. S.blend says what the frame shown is drawn with (gl.js draws it).

import { S, redraw } from "./view.js";
import { on, drawingUrl } from "./net.js";
import { GL } from "./gl.js";
import { ease, parse } from "./easing.js";

// Keyframe -> the key of the look loaded (or loading) for it: `${rev}:${name}`.
const loaded = new Map();

function load(k, key) {
  loaded.set(k, key);
  const img = new Image();
  const picture = new Promise((ok, fail) => { img.onload = ok; img.onerror = fail; img.src = drawingUrl(k, false, key); });
  const uv = fetch(drawingUrl(k, true, key)).then((r) => (r.ok ? r.arrayBuffer() : Promise.reject(new Error(r.statusText))));
  Promise.all([picture, uv]).then(([, buffer]) => {
    if (loaded.get(k) !== key) return;
    GL.setLook(k, img, new Float32Array(buffer));
    redraw();
  }).catch(() => {
    // Drawn with the rest picture; tried again on the next change.
    if (loaded.get(k) === key) loaded.delete(k);
  });
}

function sync() {
  const st = S.state;
  if (!st) return;
  st.keyframes.forEach((key, k) => {
    if (!key.drawing) return;
    const want = `${key.rev}:${key.drawing}:${S.n}`;
    if (loaded.get(k) !== want) load(k, want);
  });
  for (const k of [...loaded.keys()]) {
    if (!st.keyframes[k] || !st.keyframes[k].drawing) { loaded.delete(k); GL.dropLook(k); }
  }
  for (const k of GL.looks()) if (!loaded.has(k)) GL.dropLook(k);
  S.blend = blend();
}

// The look of keyframe k: itself if it has a drawing, else the rest picture (-1).
const lookOf = (k) => (S.state.keyframes[k] && S.state.keyframes[k].drawing ? k : -1);

// What the shape shown is drawn with.
export function blend() {
  const st = S.state;
  if (!st || !st.keyframes.length) return { a: -1, b: -1, w: 0 };
  if (S.showing === "pose") {
    const k = S.frameInfo.keyframe >= 0 ? S.frameInfo.keyframe : st.current;
    return { a: lookOf(k), b: lookOf(k), w: 0 };
  }
  const keys = st.keyframes, t = S.frameInfo.time;
  if (keys.length < 2) return { a: lookOf(0), b: lookOf(0), w: 0 };
  let k = 0;
  while (k < keys.length - 2 && keys[k + 1].time <= t) k++;
  const span = keys[k + 1].time - keys[k].time;
  const u = Math.min(1, Math.max(0, span > 0 ? (t - keys[k].time) / span : 0));
  const e = ease(parse(keys[k].easing), u);
  return { a: lookOf(k), b: lookOf(k + 1), w: e * e * (3 - 2 * e) };
}

on("state", () => { sync(); redraw(); });
on("frame", () => { S.blend = blend(); });
on("mesh", () => {
  // New corners: every look is fetched again for the new mesh.
  for (const k of [...loaded.keys()]) GL.dropLook(k);
  loaded.clear();
  sync();
});
