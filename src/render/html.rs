//! The self-contained HTML viewer: one page, no network, every frame embedded.
//!
//! The page holds a `<canvas>` (`id="view"`) drawing the mesh of the current frame (filled
//! triangles and edges, triangles with non-positive signed area in red, or each triangle
//! textured through its corners' texture coordinates), a slider over the frames (`id="t"`)
//! with the frame's `t` shown next to it, a play/pause button (`id="play"`, loops) and an edge
//! toggle (`id="edges"`). The left/right arrow keys step through the frames, space plays or
//! pauses. The canvas keeps the viewport's aspect ratio and follows the window's size.
//!
//! The URL fragment selects the first frame shown: `page.html#frame=N` (0-based) or
//! `page.html#t=0.5` (the frame whose `t` is nearest); `#play` starts playing, as in
//! `page.html#t=0.5&play`. After every drawing the page sets
//! `document.body.dataset.frame` (the `data-frame` attribute of `<body>`) to the frame's
//! index, so a browser driver can wait for it.
//!
//! ## Size
//!
//! Positions are stored relative to the viewport's centre, rounded to `f32` (little-endian),
//! one base64 string per frame: 8 bytes, 10⅔ characters of page, per vertex per frame. The
//! triangles are stored once (12 bytes, 16 characters each), texture coordinates likewise
//! (24 bytes, 32 characters per triangle), the texture as the PNG given, base64-encoded.
//! Frames are decoded when first shown. A browser holds a string of at most about 2²⁹
//! characters, so one frame can have about 50 million vertices.
//!
//! ```
//! use bdmorph::render::{html::html, Viewport};
//! let a: &[[f64; 2]] = &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
//! let b: &[[f64; 2]] = &[[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
//! let view = Viewport::fit([a, b]);
//! let page = html("A <triangle>", &[(0.0, a), (1.0, b)], &[[0, 1, 2]], None, None, &view);
//! assert!(page.starts_with("<!DOCTYPE html>"));
//! assert!(page.contains("<title>A &lt;triangle&gt;</title>"));
//! ```

use std::fmt::Write;

use super::colour::shade_colour;
use super::Viewport;

/// A self-contained HTML page animating `frames` (each a time `t` and one position per
/// vertex) of the mesh with triangles `faces`, every frame showing the world rectangle `view`.
///
/// With `corner_uv` (parallel to `faces`, `(0, 0)` the image's bottom-left corner) and
/// `texture_png` (a PNG file's bytes), each triangle is drawn textured; without either, or
/// when `corner_uv` is not as long as `faces`, triangles are filled flat. Nothing here panics
/// on odd input: frames shorter than the longest are padded with missing vertices, and a
/// triangle with a missing, non-finite or out-of-range vertex is not drawn. `title` is
/// HTML-escaped; it is the only text from the caller that the page contains.
pub fn html(
    title: &str,
    frames: &[(f64, &[[f64; 2]])],
    faces: &[[u32; 3]],
    corner_uv: Option<&[[[f64; 2]; 3]]>,
    texture_png: Option<&[u8]>,
    view: &Viewport,
) -> String {
    html_shaded(title, frames, faces, corner_uv, texture_png, None, view)
}

/// Per-frame shades of the triangles for [`html_shaded`], drawn instead of the flat fill and
/// the texture, with a legend.
#[derive(Clone, Copy, Debug)]
pub struct Shading<'a> {
    /// One shade per face (0 to 255, coloured by [`super::colour::shade_colour`]) for each
    /// frame; a frame without one face's worth is drawn flat.
    pub shades: &'a [Vec<u8>],
    /// What the shades show, for the legend (HTML-escaped).
    pub label: &'a str,
    /// The value of the brightest shade; the darkest is 1 (logarithmic scale).
    pub max: f64,
}

/// As [`html`], with the triangles of each frame coloured by `shading` when given: the page
/// then shows a colour bar from 1 to `shading.max` beside the slider (`id="legend"`).
pub fn html_shaded(
    title: &str,
    frames: &[(f64, &[[f64; 2]])],
    faces: &[[u32; 3]],
    corner_uv: Option<&[[[f64; 2]; 3]]>,
    texture_png: Option<&[u8]>,
    shading: Option<&Shading>,
    view: &Viewport,
) -> String {
    let vertices = frames.iter().map(|(_, p)| p.len()).max().unwrap_or(0);
    let centre = [
        0.5 * (view.min[0] + view.max[0]),
        0.5 * (view.min[1] + view.max[1]),
    ];
    let centre = centre.map(|c| if c.is_finite() { c } else { 0.0 });
    let extent = |d: usize| {
        let e = view.max[d] - view.min[d];
        if e.is_finite() && e > 0.0 {
            e
        } else {
            1.0
        }
    };
    let size = [extent(0), extent(1)];
    let texture = match (corner_uv, texture_png) {
        (Some(uv), Some(png)) if uv.len() == faces.len() => Some((uv, png)),
        _ => None,
    };
    // Faces that cannot be drawn in any frame are dropped here, with their texture coordinates.
    let kept: Vec<usize> = (0..faces.len())
        .filter(|&f| faces[f].iter().all(|&v| (v as usize) < vertices))
        .collect();

    let title = escape(title);
    let frame_chars = (vertices * 8).div_ceil(3) * 4 + 3;
    let mut out = String::with_capacity(8192 + frames.len() * frame_chars + kept.len() * 48);
    out.push_str(HEAD);
    let _ = write!(
        out,
        "<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n"
    );
    let _ = write!(
        out,
        "<div id=\"bar\"><span id=\"name\">{title}</span>\
         <button id=\"play\" type=\"button\">Play</button>\
         <input id=\"t\" type=\"range\" min=\"0\" max=\"{max}\" step=\"1\" value=\"0\" \
         aria-label=\"frame\"><span id=\"label\"></span>\
         <label><input id=\"edges\" type=\"checkbox\"{checked}> edges</label>{legend}</div>\n\
         <div id=\"stage\"><canvas id=\"view\"></canvas></div>\n",
        max = frames.len().saturating_sub(1),
        checked = if texture.is_some() && shading.is_none() {
            ""
        } else {
            " checked"
        },
        legend = match shading {
            Some(sh) => {
                let stops: Vec<String> = (0..=8)
                    .map(|i| {
                        let [r, g, b] = shade_colour((i * 255 / 8) as u8);
                        format!("#{r:02x}{g:02x}{b:02x}")
                    })
                    .collect();
                format!(
                    "<span id=\"legend\">{label} 1 <span class=\"ramp\" \
                     style=\"background:linear-gradient(to right,{stops})\"></span> {max}</span>",
                    label = escape(sh.label),
                    stops = stops.join(","),
                    max = number(sh.max),
                )
            }
            None => String::new(),
        },
    );
    if let Some((_, png)) = texture {
        out.push_str("<img id=\"texture\" hidden alt=\"\" src=\"data:image/png;base64,");
        base64_into(&mut out, png);
        out.push_str("\">\n");
    }

    // The data: numbers and base64 strings only.
    out.push_str("<script>\n\"use strict\";\nconst DATA = {\n");
    let _ = writeln!(out, "vertices: {vertices},");
    let _ = writeln!(
        out,
        "centre: [{}, {}],\nsize: [{}, {}],",
        number(centre[0]),
        number(centre[1]),
        number(size[0]),
        number(size[1])
    );
    out.push_str("times: [");
    for (i, (t, _)) in frames.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&number(*t));
    }
    out.push_str("],\nfaces: \"");
    let mut bytes = Vec::with_capacity(kept.len() * 12);
    for &f in &kept {
        for v in faces[f] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    base64_into(&mut out, &bytes);
    out.push_str("\",\nuv: ");
    if let Some((uv, _)) = texture {
        bytes.clear();
        for &f in &kept {
            for c in uv[f] {
                for x in c {
                    bytes.extend_from_slice(&(x as f32).to_le_bytes());
                }
            }
        }
        out.push('"');
        base64_into(&mut out, &bytes);
        out.push('"');
    } else {
        out.push_str("null");
    }
    out.push_str(",\nshades: ");
    match shading {
        Some(sh) => {
            out.push_str("[\n");
            for i in 0..frames.len() {
                out.push('"');
                if let Some(frame) = sh.shades.get(i).filter(|s| s.len() == faces.len()) {
                    bytes.clear();
                    bytes.extend(kept.iter().map(|&f| frame[f]));
                    base64_into(&mut out, &bytes);
                }
                out.push_str("\",\n");
            }
            out.push_str("],\npalette: [");
            for s in 0..=255u8 {
                let [r, g, b] = shade_colour(s);
                let _ = write!(
                    out,
                    "{}\"#{r:02x}{g:02x}{b:02x}\"",
                    if s > 0 { "," } else { "" }
                );
            }
            out.push(']');
        }
        None => out.push_str("null,\npalette: null"),
    }
    out.push_str(",\nframes: [\n");
    for (i, (_, positions)) in frames.iter().enumerate() {
        bytes.clear();
        for v in 0..vertices {
            let p = positions.get(v).copied().unwrap_or([f64::NAN; 2]);
            for d in 0..2 {
                bytes.extend_from_slice(&((p[d] - centre[d]) as f32).to_le_bytes());
            }
        }
        out.push('"');
        base64_into(&mut out, &bytes);
        out.push_str(if i + 1 < frames.len() {
            "\",\n"
        } else {
            "\"\n"
        });
    }
    out.push_str("]\n};\n");
    out.push_str(SCRIPT);
    out.push_str("</script>\n</body>\n</html>\n");
    out
}

const HEAD: &str = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; \
script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:\">\n\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";

const STYLE: &str = "\
html,body{margin:0;height:100%;background:#fff;color:#222;font:14px system-ui,sans-serif}\
body{display:flex;flex-direction:column;overflow:hidden}\
#bar{display:flex;align-items:center;gap:8px;padding:6px 10px;flex:none}\
#name{font-weight:600;white-space:nowrap;overflow:hidden;text-overflow:ellipsis;max-width:30%}\
#name:empty{display:none}\
input{accent-color:#555}\
#t{flex:1;min-width:60px}\
#label{font-variant-numeric:tabular-nums;white-space:nowrap}\
#stage{flex:1;min-height:0;display:flex;align-items:center;justify-content:center}\
canvas{display:block}\
#legend{display:flex;align-items:center;gap:4px;white-space:nowrap}\
.ramp{display:inline-block;width:90px;height:10px;border:1px solid #888}";

/// The viewer; reads `DATA`.
const SCRIPT: &str = r##"(function () {
  const littleEndian = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;
  function bytes(b64) {
    const s = atob(b64);
    const u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return u;
  }
  function floats(b64) {
    const u = bytes(b64);
    const n = u.length >> 2;
    if (littleEndian) return new Float32Array(u.buffer, 0, n);
    const d = new DataView(u.buffer), out = new Float32Array(n);
    for (let i = 0; i < n; i++) out[i] = d.getFloat32(4 * i, true);
    return out;
  }
  function uints(b64) {
    const u = bytes(b64);
    const n = u.length >> 2;
    if (littleEndian) return new Uint32Array(u.buffer, 0, n);
    const d = new DataView(u.buffer), out = new Uint32Array(n);
    for (let i = 0; i < n; i++) out[i] = d.getUint32(4 * i, true);
    return out;
  }

  const NV = DATA.vertices, NT = DATA.frames.length;
  const F = uints(DATA.faces), NF = F.length / 3;
  const UV = DATA.uv === null ? null : floats(DATA.uv);
  const SHADES = DATA.shades, decodedShades = new Array(NT);
  function shades(i) {
    if (SHADES === null || SHADES[i] === undefined || SHADES[i].length === 0) return null;
    if (!decodedShades[i]) decodedShades[i] = bytes(SHADES[i]);
    return decodedShades[i].length === NF ? decodedShades[i] : null;
  }
  const decoded = new Array(NT);
  function positions(i) {
    if (!decoded[i]) decoded[i] = floats(DATA.frames[i]);
    return decoded[i];
  }

  const canvas = document.getElementById("view");
  const ctx = canvas.getContext("2d");
  const slider = document.getElementById("t");
  const label = document.getElementById("label");
  const play = document.getElementById("play");
  const edges = document.getElementById("edges");
  const stage = document.getElementById("stage");
  const img = document.getElementById("texture");
  const X = new Float64Array(NV), Y = new Float64Array(NV);
  let frame = 0;

  const GROW = 0.75;
  function textureReady() {
    return UV !== null && img !== null && img.complete && img.naturalWidth > 0;
  }

  // Maps the texture's triangle (image pixels) onto the screen triangle a, b, c of face f.
  function texturedTriangle(f, a, b, c, dpr) {
    // Texture coordinates have v up, image rows go down.
    const w = img.naturalWidth, h = img.naturalHeight, o = 6 * f;
    const u0 = UV[o] * w, v0 = (1 - UV[o + 1]) * h;
    const u1 = UV[o + 2] * w, v1 = (1 - UV[o + 3]) * h;
    const u2 = UV[o + 4] * w, v2 = (1 - UV[o + 5]) * h;
    const du1 = u1 - u0, dv1 = v1 - v0, du2 = u2 - u0, dv2 = v2 - v0;
    const det = du1 * dv2 - du2 * dv1;
    const x0 = X[a], y0 = Y[a], dx1 = X[b] - x0, dy1 = Y[b] - y0, dx2 = X[c] - x0, dy2 = Y[c] - y0;
    if (!(Math.abs(det) > 1e-12)) return false;
    const m11 = (dx1 * dv2 - dx2 * dv1) / det, m12 = (dx2 * du1 - dx1 * du2) / det;
    const m21 = (dy1 * dv2 - dy2 * dv1) / det, m22 = (dy2 * du1 - dy1 * du2) / det;
    const e = x0 - m11 * u0 - m12 * v0, g = y0 - m21 * u0 - m22 * v0;
    if (![m11, m12, m21, m22, e, g].every(Number.isFinite)) return false;
    // Clip to the screen triangle with its edges pushed out by GROW pixels (a hexagon: the
    // corners bevelled), hiding the seams between neighbours' anti-aliased clips.
    const side = dx1 * dy2 - dx2 * dy1 > 0 ? 1 : -1, grow = GROW * dpr;
    const vs = [a, b, c], nx = [0, 0, 0], ny = [0, 0, 0];
    for (let k = 0; k < 3; k++) {
      const p = vs[k], q = vs[(k + 1) % 3];
      const ex = X[q] - X[p], ey = Y[q] - Y[p], l = Math.hypot(ex, ey);
      if (!(l > 0)) return false;
      nx[k] = (side * ey) / l;
      ny[k] = (-side * ex) / l;
    }
    // The texture is drawn over the grown triangle's bounding box in texture space (found
    // through the inverse map), plus a texel, clamped to the image.
    const inv = 1 / (m11 * m22 - m12 * m21);
    let umin = Infinity, umax = -Infinity, vmin = Infinity, vmax = -Infinity;
    ctx.save();
    ctx.beginPath();
    for (let k = 0; k < 6; k++) {
      // Vertex k >> 1 moved out along the normal of the edge ending there, then of the edge
      // starting there.
      const p = vs[k >> 1], n = k & 1 ? k >> 1 : ((k >> 1) + 2) % 3;
      const x = X[p] + grow * nx[n], y = Y[p] + grow * ny[n];
      ctx.lineTo(x, y);
      const u = inv * (m22 * (x - e) - m12 * (y - g)), v = inv * (m11 * (y - g) - m21 * (x - e));
      umin = Math.min(umin, u); umax = Math.max(umax, u);
      vmin = Math.min(vmin, v); vmax = Math.max(vmax, v);
    }
    ctx.closePath();
    ctx.clip();
    ctx.setTransform(m11, m21, m12, m22, e, g);
    const sx = Math.max(0, Math.floor(umin) - 1), sy = Math.max(0, Math.floor(vmin) - 1);
    const sw = Math.min(w, Math.ceil(umax) + 1) - sx, sh = Math.min(h, Math.ceil(vmax) + 1) - sy;
    if (sw > 0 && sh > 0) ctx.drawImage(img, sx, sy, sw, sh, sx, sy, sw, sh);
    ctx.restore();
    return true;
  }

  function draw() {
    const W = canvas.width, H = canvas.height, dpr = window.devicePixelRatio || 1;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#fff";
    ctx.fillRect(0, 0, W, H);
    if (NT > 0) {
      const P = positions(frame);
      const s = Math.min(W / DATA.size[0], H / DATA.size[1]);
      for (let v = 0; v < NV; v++) {
        X[v] = 0.5 * W + s * P[2 * v];
        Y[v] = 0.5 * H - s * P[2 * v + 1]; // world y up, screen y down
      }
      const S = shades(frame);
      const textured = S === null && textureReady();
      const good = new Path2D(), bad = new Path2D(), lines = new Path2D();
      const buckets = S === null ? null : new Map();
      for (let f = 0; f < NF; f++) {
        const a = F[3 * f], b = F[3 * f + 1], c = F[3 * f + 2];
        if (!(Number.isFinite(X[a] + Y[a] + X[b] + Y[b] + X[c] + Y[c]))) continue;
        // Signed area in world coordinates: non-positive means flipped.
        const ax = P[2 * a], ay = P[2 * a + 1];
        const area = (P[2 * b] - ax) * (P[2 * c + 1] - ay) - (P[2 * c] - ax) * (P[2 * b + 1] - ay);
        let path = area > 0 ? good : bad;
        if (area > 0 && S !== null) {
          path = buckets.get(S[f]);
          if (path === undefined) { path = new Path2D(); buckets.set(S[f], path); }
        }
        if (area > 0 && textured && texturedTriangle(f, a, b, c, dpr)) {
          // drawn
        } else {
          path.moveTo(X[a], Y[a]);
          path.lineTo(X[b], Y[b]);
          path.lineTo(X[c], Y[c]);
          path.closePath();
        }
        lines.moveTo(X[a], Y[a]);
        lines.lineTo(X[b], Y[b]);
        lines.lineTo(X[c], Y[c]);
        lines.closePath();
      }
      ctx.fillStyle = "#9cc1ec";
      ctx.fill(good);
      if (buckets !== null) {
        for (const [shade, path] of buckets) {
          ctx.fillStyle = DATA.palette[shade];
          ctx.fill(path);
        }
      }
      ctx.fillStyle = "#e0201b";
      ctx.fill(bad);
      if (edges.checked) {
        ctx.strokeStyle = "#24466e";
        ctx.lineWidth = 0.75 * dpr;
        ctx.lineJoin = "round";
        ctx.stroke(lines);
      }
      const t = DATA.times[frame];
      label.textContent = "t = " + (t === null ? "?" : String(+t.toPrecision(6))) +
        " (" + (frame + 1) + "/" + NT + ")";
    } else {
      label.textContent = "no frames";
    }
    document.body.dataset.frame = String(frame);
  }

  function resize() {
    const aw = Math.max(1, stage.clientWidth - 16), ah = Math.max(1, stage.clientHeight - 16);
    const aspect = DATA.size[0] / DATA.size[1];
    let w = aw, h = aw / aspect;
    if (h > ah) { h = ah; w = ah * aspect; }
    const dpr = window.devicePixelRatio || 1;
    canvas.style.width = w + "px";
    canvas.style.height = h + "px";
    canvas.width = Math.max(1, Math.round(w * dpr));
    canvas.height = Math.max(1, Math.round(h * dpr));
    draw();
  }

  function show(i) {
    frame = NT > 0 ? Math.min(NT - 1, Math.max(0, Math.trunc(i) || 0)) : 0;
    slider.value = String(frame);
    draw();
  }

  // Playing loops through the frames in about 3 s (at most 30 frames a second).
  let playing = false, timer = 0;
  const step = NT > 1 ? Math.max(1000 / 30, 3000 / (NT - 1)) : 1000;
  function tick() {
    if (!playing) return;
    show((frame + 1) % NT);
    timer = setTimeout(tick, step);
  }
  function setPlaying(on) {
    playing = on && NT > 1;
    play.textContent = playing ? "Pause" : "Play";
    clearTimeout(timer);
    if (playing) timer = setTimeout(tick, step);
  }

  function fromHash() {
    const h = location.hash.replace(/^#/, "");
    for (const part of h.split("&")) {
      const [key, value] = part.split("=");
      const x = Number(value);
      if (key === "frame" && value !== undefined && value !== "" && Number.isFinite(x)) {
        show(Math.round(x));
      } else if (key === "t" && value !== undefined && value !== "" && Number.isFinite(x)) {
        let best = 0, gap = Infinity;
        DATA.times.forEach(function (t, i) {
          if (t !== null && Math.abs(t - x) < gap) { gap = Math.abs(t - x); best = i; }
        });
        show(best);
      } else if (key === "play") {
        setPlaying(true);
      }
    }
  }

  slider.addEventListener("input", function () { setPlaying(false); show(Number(slider.value)); });
  play.addEventListener("click", function () { setPlaying(!playing); });
  edges.addEventListener("change", draw);
  document.addEventListener("keydown", function (e) {
    if (e.target === slider && (e.key === "ArrowLeft" || e.key === "ArrowRight")) return;
    if (e.key === "ArrowLeft" || e.key === "ArrowRight") {
      setPlaying(false);
      show(frame + (e.key === "ArrowRight" ? 1 : -1));
      e.preventDefault();
    } else if (e.key === " " && !(e.target instanceof HTMLButtonElement ||
                                  e.target instanceof HTMLInputElement)) {
      setPlaying(!playing);
      e.preventDefault();
    }
  });
  window.addEventListener("resize", resize);
  window.addEventListener("hashchange", fromHash);
  if (img !== null) img.addEventListener("load", draw);
  slider.disabled = NT < 2;
  play.disabled = NT < 2;
  fromHash();
  resize();
})();
"##;

/// A self-contained page of still pictures (PNG files' bytes), each with a caption, under a
/// title and a line of legend: for fields drawn by [`super::surface::render_field`]. No
/// script; captions, title and legend are HTML-escaped.
///
/// ```
/// use bdmorph::render::html::picture_page;
/// let page = picture_page("t", "0 <- distance -> 1", &[("source 0".into(), vec![1, 2, 3])]);
/// assert!(page.contains("<figcaption>source 0</figcaption>"));
/// assert!(page.contains("data:image/png;base64,AQID"));
/// ```
pub fn picture_page(title: &str, legend: &str, pictures: &[(String, Vec<u8>)]) -> String {
    let title = escape(title);
    let mut out = String::with_capacity(
        4096 + pictures
            .iter()
            .map(|p| p.1.len() * 4 / 3 + 200)
            .sum::<usize>(),
    );
    out.push_str(HEAD);
    let _ = write!(
        out,
        "<title>{title}</title>\n<style>body{{margin:16px;font:14px system-ui,sans-serif;color:#222}}\
         figure{{display:inline-block;margin:0 16px 16px 0}}img{{max-width:100%;border:1px solid #ddd}}\
         .ramp{{display:inline-block;width:140px;height:10px;border:1px solid #888;vertical-align:middle}}</style>\n\
         </head>\n<body>\n<h1 style=\"font-size:18px\">{title}</h1>\n<p id=\"legend\">{legend}</p>\n",
        legend = escape(legend),
    );
    for (caption, png) in pictures {
        out.push_str("<figure><img alt=\"\" src=\"data:image/png;base64,");
        base64_into(&mut out, png);
        let _ = writeln!(
            out,
            "\"><figcaption>{}</figcaption></figure>",
            escape(caption)
        );
    }
    out.push_str("</body>\n</html>\n");
    out
}

/// A number for a script: the shortest text that reads back exactly, `null` if not finite.
fn number(x: f64) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        "null".to_string()
    }
}

/// `text` safe inside HTML element content and attribute values.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// Appends the standard base64 (RFC 4648, with `=` padding) of `bytes`.
fn base64_into(out: &mut String, bytes: &[u8]) {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.reserve(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            out.push(if i <= chunk.len() {
                char::from(ALPHABET[(n >> shift & 63) as usize])
            } else {
                '='
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base64(bytes: &[u8]) -> String {
        let mut s = String::new();
        base64_into(&mut s, bytes);
        s
    }

    /// Decodes what `base64_into` wrote (test only).
    fn unbase64(s: &str) -> Vec<u8> {
        let value = |c: u8| match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        };
        let mut out = Vec::new();
        for chunk in s.as_bytes().chunks(4) {
            let data: Vec<u8> = chunk.iter().copied().filter(|&c| c != b'=').collect();
            let n = data
                .iter()
                .enumerate()
                .fold(0u32, |n, (i, &c)| n | u32::from(value(c)) << (18 - 6 * i));
            out.extend((0..data.len() - 1).map(|i| (n >> (16 - 8 * i)) as u8));
        }
        out
    }

    fn triangle_page(frames: usize, texture: bool) -> String {
        let positions: Vec<Vec<[f64; 2]>> = (0..frames)
            .map(|i| vec![[0.0, 0.0], [1.0 + i as f64, 0.0], [0.0, 1.0]])
            .collect();
        let frames: Vec<(f64, &[[f64; 2]])> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| (i as f64 / (frames.max(2) - 1) as f64, p.as_slice()))
            .collect();
        let view = Viewport::fit(frames.iter().map(|f| f.1));
        let uv = [[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]];
        html(
            "morph",
            &frames,
            &[[0, 1, 2]],
            texture.then_some(&uv[..]),
            texture.then_some(&b"\x89PNG\r\n\x1a\n"[..]),
            &view,
        )
    }

    /// The base64 strings of the `frames: [...]` array.
    fn embedded_frames(page: &str) -> Vec<&str> {
        let start = page.find("frames: [\n").expect("frames array") + "frames: [\n".len();
        let end = start + page[start..].find("]\n};").expect("end of frames");
        page[start..end]
            .lines()
            .map(|l| l.trim_end_matches(',').trim_matches('"'))
            .collect()
    }

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        let vectors = [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ];
        for (plain, encoded) in vectors {
            assert_eq!(base64(plain.as_bytes()), encoded, "{plain:?}");
        }
        let all: Vec<u8> = (0..=255).collect();
        let encoded = base64(&all);
        assert!(encoded.ends_with("+/w=="), "{encoded}");
        assert_eq!(unbase64(&encoded), all);
    }

    #[test]
    fn page_is_self_contained_and_drivable() {
        for texture in [false, true] {
            let page = triangle_page(3, texture);
            assert!(!page.contains("http://") && !page.contains("https://"));
            assert!(!page.contains("<script src") && !page.contains("<link"));
            assert!(!page.contains("url("), "no CSS fetches");
            for id in ["id=\"t\"", "id=\"play\"", "id=\"view\"", "dataset.frame"] {
                assert!(page.contains(id), "{id}");
            }
            assert_eq!(page.contains("data:image/png;base64,iVBORw0KGgo="), texture);
            assert_eq!(page.contains("uv: null"), !texture);
        }
    }

    #[test]
    fn every_frame_is_embedded_as_f32_relative_to_the_centre() {
        for n in [0, 1, 11] {
            let page = triangle_page(n, false);
            let frames = embedded_frames(&page);
            assert_eq!(frames.len(), n, "{n} frames");
            assert_eq!(page.contains("times: []"), n == 0);
            assert!(page.contains(&format!("max=\"{}\"", n.saturating_sub(1))));
        }
        let page = triangle_page(11, false);
        let frames = embedded_frames(&page);
        // Viewport of all frames: x in [0, 11], y in [0, 1], 5 % margins of 11.
        let bytes = unbase64(frames[10]);
        assert_eq!(bytes.len(), 3 * 2 * 4, "3 vertices, 2 f32 each");
        let f: Vec<f32> = bytes
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let expected = [-5.5, -0.5, 5.5, -0.5, -5.5, 0.5];
        for (got, want) in f.iter().zip(expected) {
            assert!((got - want).abs() < 1e-6, "{f:?}");
        }
        assert!(page.contains("times: [0.0,0.1,0.2,"));
        assert!(page.contains(&format!(
            "faces: \"{}\"",
            base64(&[0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0])
        )));
    }

    #[test]
    fn titles_are_escaped_and_nothing_else_reaches_the_script() {
        let p: &[[f64; 2]] = &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let view = Viewport::fit([p]);
        let title = "</script><script>alert('x & \"y\"')</script>";
        let page = html(title, &[(f64::NAN, p)], &[[0, 1, 2]], None, None, &view);
        assert!(page.contains(
            "&lt;/script&gt;&lt;script&gt;alert(&#39;x &amp; &quot;y&quot;&#39;)&lt;/script&gt;"
        ));
        assert!(!page.contains("alert('"));
        assert_eq!(page.matches("<script>").count(), 1);
        assert!(
            page.contains("times: [null]"),
            "non-finite numbers become null"
        );
    }

    #[test]
    fn odd_input_is_dropped_not_a_panic() {
        let short: &[[f64; 2]] = &[[0.0, 0.0], [1.0, 0.0]];
        let long: &[[f64; 2]] = &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [f64::INFINITY, 0.0]];
        let faces = [[0, 1, 2], [0, 1, 9]];
        let uv = [[[0.0; 2]; 3]]; // shorter than faces: no texture
        let view = Viewport {
            min: [0.0, 0.0],
            max: [0.0, f64::NAN],
        };
        let frames = [(0.0, short), (1.0, long)];
        let page = html("", &frames, &faces, Some(&uv), Some(b"png"), &view);
        assert!(page.contains("vertices: 4,"));
        assert!(page.contains("size: [1.0, 1.0],"));
        assert!(page.contains("uv: null"));
        assert!(!page.contains("data:image"));
        assert_eq!(unbase64(embedded_frames(&page)[0]).len(), 4 * 2 * 4);
        let faces_b64 = base64(&[0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        assert!(
            page.contains(&format!("faces: \"{faces_b64}\"")),
            "face 2 dropped"
        );
    }
}
