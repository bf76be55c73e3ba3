// The mesh drawn by WebGL 2: triangles expanded (three corners each) so that each carries its
// own distortion and a barycentric coordinate; the fragment shader colours by the distortion
// ramp (or samples the picture) and draws the edges from the barycentrics, in one pass. A
// second pass draws flipped triangles on top in a strong colour, whatever else is shown, so
// a fold is never hidden under the picture or under the triangles that cover it.
//
// Keyframes made from drawings bring their own pictures ("looks": a texture and coordinates
// per keyframe, looks.js loads them): between two keyframes of different pictures the two are
// sampled and cross-faded by S.blend = { a, b, w } (a look's keyframe, or -1 for the rest
// picture, and the second's share).

import { S, $ } from "./view.js";

const glCanvas = $("gl");
const gl = glCanvas.getContext("webgl2", { antialias: false, premultipliedAlpha: false });

const none = { kind: "2d", ready: () => false, setMesh() {}, setTexture() {}, setLook() {}, dropLook() {}, looks: () => [], draw() {} };

function make() {
  if (!gl) return none;
  const vs = `#version 300 es
    in vec2 position; in float distortion; in vec3 bary; in vec2 uv; in vec2 uv2;
    uniform vec3 view; uniform vec2 size;
    out float d; out vec3 b; out vec2 t; out vec2 t2;
    void main() {
      vec2 p = vec2(view.y + view.x * position.x, view.z - view.x * position.y);
      gl_Position = vec4(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y, 0.0, 1.0);
      d = distortion; b = bary; t = uv; t2 = uv2;
    }`;
  const fs = `#version 300 es
    precision highp float;
    in float d; in vec3 b; in vec2 t; in vec2 t2;
    uniform float top; uniform int mode; uniform bool edges; uniform float alpha; uniform sampler2D picture;
    uniform sampler2D picture2; uniform float fade;
    out vec4 colour;
    vec3 ramp(float s) {
      vec3 c0 = vec3(68, 1, 84) / 255.0, c1 = vec3(59, 82, 139) / 255.0, c2 = vec3(33, 145, 140) / 255.0,
           c3 = vec3(94, 201, 98) / 255.0, c4 = vec3(253, 231, 37) / 255.0;
      s = clamp(s, 0.0, 1.0) * 4.0;
      if (s < 1.0) return mix(c0, c1, s);
      if (s < 2.0) return mix(c1, c2, s - 1.0);
      if (s < 3.0) return mix(c2, c3, s - 2.0);
      return mix(c3, c4, s - 3.0);
    }
    void main() {
      vec3 c;
      float a = alpha;
      if (mode == 3) {
        // A flipped triangle: magenta with dark stripes, opaque.
        if (d < 1e30) discard;
        float stripe = step(0.5, fract((gl_FragCoord.x + gl_FragCoord.y) / 8.0));
        c = mix(vec3(1.0, 0.0, 0.8), vec3(0.35, 0.0, 0.3), stripe * 0.6);
        colour = vec4(c, 1.0);
        return;
      }
      if (!(d < 1e30)) c = vec3(1.0, 0.0, 0.8);
      else if (mode == 1) c = ramp(log(max(d, 1.0)) / log(max(top, 1.05)));
      else if (mode == 2) {
        vec4 s = texture(picture, t);
        if (fade > 0.0) {
          // Mixed in premultiplied space: a transparent part fades rather than darkens.
          vec4 s2 = texture(picture2, t2);
          vec4 m = mix(vec4(s.rgb * s.a, s.a), vec4(s2.rgb * s2.a, s2.a), fade);
          s = m.a > 0.0 ? vec4(m.rgb / m.a, m.a) : vec4(0.0);
        }
        c = mix(vec3(1.0), s.rgb, s.a);
      }
      else c = vec3(0.725, 0.827, 0.933);
      if (edges) {
        vec3 w = fwidth(b);
        vec3 e = smoothstep(vec3(0.0), 1.2 * w, b);
        float edge = 1.0 - min(min(e.x, e.y), e.z);
        c = mix(c, vec3(1.0), 0.35 * edge);
        if (alpha < 1.0) a = alpha * edge;
      }
      colour = vec4(c, a);
    }`;
  const compile = (type, src) => {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, src);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
    return sh;
  };
  let program;
  try {
    program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, vs));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  } catch (e) {
    console.warn("WebGL unavailable, drawing on the 2D canvas:", e);
    return none;
  }
  const loc = (n) => gl.getAttribLocation(program, n);
  const uni = (n) => gl.getUniformLocation(program, n);
  const buffers = { position: gl.createBuffer(), distortion: gl.createBuffer(), bary: gl.createBuffer(), uv: gl.createBuffer(), rest: gl.createBuffer() };
  // Keyframe k's look: { texture, buffer (its coordinates per corner), uv (per vertex) }.
  const looks = new Map();
  let corners = 0, pos = null, dis = null, restPos = null, texture = null;
  const attrib = (buffer, name, size) => {
    const l = loc(name);
    if (l < 0) return;
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.enableVertexAttribArray(l);
    gl.vertexAttribPointer(l, size, gl.FLOAT, false, 0, 0);
  };
  // Corner c of the expanded triangles is corner c % 3 of triangle faceOf(c): the triangles
  // in the painted draw order (by depth, as every export draws them), later ones on top.
  const faceOf = (c) => (S.order ? S.order[(c / 3) | 0] : (c / 3) | 0);
  const vertexOf = (c) => S.faces[3 * faceOf(c) + (c % 3)];
  const expand = (src, out) => {
    for (let c = 0; c < corners; c++) {
      // A hidden part's triangles collapse to a point: nothing is drawn for them.
      if (S.faceHidden && S.faceHidden[faceOf(c)]) { out[2 * c] = 0; out[2 * c + 1] = 0; continue; }
      const v = vertexOf(c);
      out[2 * c] = src[2 * v];
      out[2 * c + 1] = src[2 * v + 1];
    }
  };
  // Per-vertex texture coordinates (v up) expanded to the corners (v down), into `buffer`.
  const fillUv = (buffer, perVertex) => {
    const uv = new Float32Array(2 * corners);
    if (perVertex && perVertex.length === 2 * S.n) {
      for (let c = 0; c < corners; c++) {
        const v = vertexOf(c);
        uv[2 * c] = perVertex[2 * v];
        uv[2 * c + 1] = 1 - perVertex[2 * v + 1];
      }
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.bufferData(gl.ARRAY_BUFFER, uv, gl.STATIC_DRAW);
  };
  const makeTexture = (img) => {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, img);
    gl.generateMipmap(gl.TEXTURE_2D);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
    return t;
  };
  // The texture and coordinate buffer of look `k` (-1 or a keyframe without one: the rest
  // picture's).
  const lookOf = (k) => looks.get(k) || { texture, buffer: buffers.uv };
  return {
    kind: "webgl2",
    ready: () => corners > 0,
    setLook(k, img, uv) {
      this.dropLook(k);
      const look = { texture: makeTexture(img), buffer: gl.createBuffer(), uv };
      looks.set(k, look);
      fillUv(look.buffer, uv);
    },
    dropLook(k) {
      const look = looks.get(k);
      if (!look) return;
      gl.deleteTexture(look.texture);
      gl.deleteBuffer(look.buffer);
      looks.delete(k);
    },
    looks: () => [...looks.keys()],
    setMesh() {
      if (S.order && S.order.length !== S.m) S.order = null;
      corners = 3 * S.m;
      pos = new Float32Array(2 * corners);
      dis = new Float32Array(corners);
      restPos = new Float32Array(2 * corners);
      const bary = new Float32Array(3 * corners);
      for (let c = 0; c < corners; c++) bary[3 * c + (c % 3)] = 1;
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.bary);
      gl.bufferData(gl.ARRAY_BUFFER, bary, gl.STATIC_DRAW);
      fillUv(buffers.uv, S.uv);
      for (const look of looks.values()) fillUv(look.buffer, look.uv);
      expand(S.rest, restPos);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.rest);
      gl.bufferData(gl.ARRAY_BUFFER, restPos, gl.STATIC_DRAW);
    },
    setTexture(img) {
      if (texture) gl.deleteTexture(texture);
      texture = null;
      if (!img) return;
      texture = makeTexture(img);
    },
    draw() {
      gl.viewport(0, 0, glCanvas.width, glCanvas.height);
      if (S.theme === "dark") gl.clearColor(0.169, 0.18, 0.2, 1); else gl.clearColor(1, 1, 1, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
      if (!corners || !S.pose) return;
      gl.useProgram(program);
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
      gl.uniform3f(uni("view"), S.view.scale, S.view.x, S.view.y);
      gl.uniform2f(uni("size"), glCanvas.width, glCanvas.height);
      let top = 1, flipped = 0;
      for (let f = 0; f < S.m; f++) {
        if (S.dist[f] < 1e30) top = Math.max(top, S.dist[f]);
        else flipped++;
      }
      gl.uniform1f(uni("top"), top);
      const textured = $("texture").checked && texture && S.uv;
      const mode = textured ? 2 : $("colours").checked ? 1 : 0;
      gl.uniform1i(uni("mode"), mode);
      // The pictures of what is shown: its keyframe's, or the two of its segment.
      const blend = S.blend || { a: -1, b: -1, w: 0 };
      const first = lookOf(blend.a), second = lookOf(blend.b);
      const fading = textured && blend.w > 0 && first !== second && second.texture;
      if (first.texture) { gl.activeTexture(gl.TEXTURE0); gl.bindTexture(gl.TEXTURE_2D, first.texture); gl.uniform1i(uni("picture"), 0); }
      if (fading) { gl.activeTexture(gl.TEXTURE1); gl.bindTexture(gl.TEXTURE_2D, second.texture); gl.uniform1i(uni("picture2"), 1); }
      gl.activeTexture(gl.TEXTURE0);
      gl.uniform1f(uni("fade"), fading ? blend.w : 0);
      attrib(buffers.bary, "bary", 3);
      attrib(first.buffer, "uv", 2);
      attrib(fading ? second.buffer : first.buffer, "uv2", 2);
      if ($("overlay").checked) {
        // The rest shape's edges, faint, under the pose.
        attrib(buffers.rest, "position", 2);
        const l = loc("distortion");
        if (l >= 0) { gl.disableVertexAttribArray(l); gl.vertexAttrib1f(l, 1); }
        gl.uniform1i(uni("edges"), 1);
        gl.uniform1f(uni("alpha"), 0.35);
        gl.uniform1i(uni("mode"), 0);
        gl.drawArrays(gl.TRIANGLES, 0, corners);
        gl.uniform1i(uni("mode"), mode);
      }
      // In outline mode the rest mesh is shown: the outline is edited in its frame.
      const outlining = S.state && S.state.mode === "outline";
      expand(outlining ? S.rest : S.pose, pos);
      for (let c = 0; c < corners; c++) dis[c] = outlining ? 1 : S.dist[faceOf(c)];
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.position);
      gl.bufferData(gl.ARRAY_BUFFER, pos, gl.DYNAMIC_DRAW);
      attrib(buffers.position, "position", 2);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers.distortion);
      gl.bufferData(gl.ARRAY_BUFFER, dis, gl.DYNAMIC_DRAW);
      attrib(buffers.distortion, "distortion", 1);
      gl.uniform1i(uni("edges"), $("edges").checked ? 1 : 0);
      gl.uniform1f(uni("alpha"), 1);
      gl.drawArrays(gl.TRIANGLES, 0, corners);
      if (flipped > 0 && !outlining) {
        gl.uniform1i(uni("mode"), 3);
        gl.drawArrays(gl.TRIANGLES, 0, corners);
      }
    },
  };
}

export const GL = make();
S.renderer = GL.kind;
