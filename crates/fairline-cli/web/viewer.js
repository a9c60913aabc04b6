// WebGL2 viewer: one or two documents side by side under one camera, the
// exact highlight shading of shaders/surface.frag, overlays (exact lines,
// irregular stretches, region, wireframe, patch boundaries).
import { Camera } from './camera.js';
import { colormapTexture } from './colormap.js';

async function shaderText(name) {
  const r = await fetch(`shaders/${name}`);
  if (!r.ok) throw new Error(`shader ${name}: ${r.status}`);
  return r.text();
}

function compile(gl, type, src) {
  const s = gl.createShader(type);
  gl.shaderSource(s, src);
  gl.compileShader(s);
  return s;
}

// Compiling and linking is started here and not waited for (no status is
// asked): the GL compiles while the page fetches the geometry;
// `finishProgram` waits for it (KHR_parallel_shader_compile when offered).
async function startProgram(gl, vert, frag) {
  const p = gl.createProgram();
  const [vs, fs] = await Promise.all([shaderText(vert), shaderText(frag)]);
  const shaders = [compile(gl, gl.VERTEX_SHADER, vs), compile(gl, gl.FRAGMENT_SHADER, fs)];
  for (const sh of shaders) gl.attachShader(p, sh);
  gl.bindAttribLocation(p, 0, 'aPosition');
  gl.bindAttribLocation(p, 1, 'aNormal');
  gl.bindAttribLocation(p, 2, 'aScalar');
  gl.linkProgram(p);
  return { p, shaders, names: [vert, frag] };
}

async function finishProgram(gl, parallel, { p, shaders, names }) {
  if (parallel) {
    while (!gl.getProgramParameter(p, parallel.COMPLETION_STATUS_KHR)) await new Promise((r) => setTimeout(r, 5));
  }
  shaders.forEach((sh, i) => {
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(`${names[i]}: ${gl.getShaderInfoLog(sh)}`);
  });
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`${names.join('+')}: ${gl.getProgramInfoLog(p)}`);
  const uniforms = {};
  const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < n; i++) {
    const info = gl.getActiveUniform(p, i);
    const name = info.name.replace(/\[0\]$/, '');
    uniforms[name] = { loc: gl.getUniformLocation(p, info.name), type: info.type, size: info.size };
  }
  return { p, uniforms };
}

function setUniforms(gl, prog, values) {
  for (const [name, v] of Object.entries(values)) {
    const u = prog.uniforms[name];
    if (!u) continue;
    switch (u.type) {
      case gl.FLOAT: if (u.size > 1) { const a = new Float32Array(u.size); a.set(v.slice(0, u.size)); gl.uniform1fv(u.loc, a); } else gl.uniform1f(u.loc, v); break;
      case gl.INT: case gl.SAMPLER_2D: case gl.BOOL: gl.uniform1i(u.loc, v); break;
      case gl.FLOAT_VEC3: gl.uniform3fv(u.loc, v); break;
      case gl.FLOAT_VEC4: gl.uniform4fv(u.loc, v); break;
      case gl.FLOAT_MAT4: gl.uniformMatrix4fv(u.loc, false, v); break;
      default: break;
    }
  }
}

// Segments (pairs of points) of polylines from a frame header + data.
// Samples of θ per circular light in surface.frag (a uniform there, so that
// the GLSL compiler keeps the loop instead of unrolling it).
const THETA_SAMPLES = 48;

// Overlays drawn after all others (the hovered line, picked endpoints,
// detected irregular stretches over the continuity edges).
const ON_TOP = new Set(['hover', 'ends', 'stretches']);

export function segments(lines, data) {
  let n = 0;
  for (const l of lines) n += 2 * (l.count - 1 + (l.closed ? 1 : 0));
  const out = new Float32Array(3 * Math.max(n, 0));
  let o = 0;
  for (const l of lines) {
    const last = l.count - 1 + (l.closed ? 1 : 0);
    for (let i = 0; i < last; i++) {
      const a = l.start + i, b = l.start + ((i + 1) % l.count);
      out.set(data.subarray(3 * a, 3 * a + 3), o); o += 3;
      out.set(data.subarray(3 * b, 3 * b + 3), o); o += 3;
    }
  }
  return out;
}

export class Viewer {
  constructor(canvas) {
    this.canvas = canvas;
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    this.camera = new Camera();
    this.docs = [];
    this.wireframe = false;
    this.dirty = true;
    this.onFrame = null;
    this.frames = 0;
  }

  // Fetches the shaders and starts compiling them (see `ready`).
  async init() {
    const gl = this.gl;
    this.parallel = gl.getExtension('KHR_parallel_shader_compile');
    this.started = await Promise.all([
      startProgram(gl, 'surface.vert', 'surface.frag'),
      startProgram(gl, 'line.vert', 'line.frag'),
      startProgram(gl, 'pick.vert', 'pick.frag'),
    ]);
  }

  // Waits for the shaders started by `init` and starts drawing.
  async ready() {
    const gl = this.gl;
    [this.surface, this.line, this.pick] = await Promise.all(this.started.map((s) => finishProgram(gl, this.parallel, s)));
    this.colormap = colormapTexture(gl);
    const loop = () => {
      if (this.dirty) { this.dirty = false; this.draw(); }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  // Geometry of document k: positions/normals (f32, relative to its centre),
  // indices (u32 triangles).
  setGeometry(k, meta, positions, normals, indices) {
    const gl = this.gl;
    let d = this.docs[k];
    if (!d) {
      d = this.docs[k] = { meta, vao: gl.createVertexArray(), pos: gl.createBuffer(), nrm: gl.createBuffer(), scl: gl.createBuffer(), idx: gl.createBuffer(), overlays: {}, region: null, scalarOn: false };
      gl.bindVertexArray(d.vao);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, d.idx);
      gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, indices, gl.STATIC_DRAW);
      d.indices = indices;
      d.count = indices.length;
      gl.bindBuffer(gl.ARRAY_BUFFER, d.scl);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(positions.length / 3), gl.STATIC_DRAW);
      gl.enableVertexAttribArray(2);
      gl.vertexAttribPointer(2, 1, gl.FLOAT, false, 0, 0);
    }
    gl.bindVertexArray(d.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, d.pos);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, d.nrm);
    gl.bufferData(gl.ARRAY_BUFFER, normals, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
    d.positions = positions;
    d.pickMesh = null;
    d.ids = null;
    d.wire = null;
    this.dirty = true;
  }

  // The state to compare document k with, drawn left of `split` (0–1 of
  // the document's viewport) with the current state right of it; `null`
  // positions end the comparison. Shares the triangles and scalars of the
  // document's geometry.
  setCompare(k, positions, normals, split) {
    const gl = this.gl;
    const d = this.docs[k];
    if (!d) return;
    if (!positions) {
      if (d.compare) {
        gl.deleteBuffer(d.compare.pos);
        gl.deleteBuffer(d.compare.nrm);
        gl.deleteVertexArray(d.compare.vao);
      }
      d.compare = null;
      this.dirty = true;
      return;
    }
    if (!d.compare) {
      d.compare = { vao: gl.createVertexArray(), pos: gl.createBuffer(), nrm: gl.createBuffer(), split: 0.5 };
      gl.bindVertexArray(d.compare.vao);
      gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, d.idx);
      gl.bindBuffer(gl.ARRAY_BUFFER, d.scl);
      gl.enableVertexAttribArray(2);
      gl.vertexAttribPointer(2, 1, gl.FLOAT, false, 0, 0);
    }
    const c = d.compare;
    gl.bindVertexArray(c.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, c.pos);
    gl.bufferData(gl.ARRAY_BUFFER, positions, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, c.nrm);
    gl.bufferData(gl.ARRAY_BUFFER, normals, gl.DYNAMIC_DRAW);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
    if (split !== undefined) c.split = Math.max(0, Math.min(1, split));
    this.dirty = true;
  }

  // Moves the divider of document k's comparison (0–1 of its viewport).
  setSplit(k, split) {
    const d = this.docs[k];
    if (!d || !d.compare) return;
    d.compare.split = Math.max(0, Math.min(1, split));
    this.dirty = true;
  }

  setScalar(k, values, range) {
    const gl = this.gl;
    const d = this.docs[k];
    if (!values) { d.scalarOn = false; this.dirty = true; return; }
    gl.bindBuffer(gl.ARRAY_BUFFER, d.scl);
    gl.bufferData(gl.ARRAY_BUFFER, values, gl.STATIC_DRAW);
    d.scalarOn = true;
    d.scalarRange = range;
    this.dirty = true;
  }

  // A line overlay: segment endpoints (f32 pairs) and an RGBA colour.
  setOverlay(k, name, segs, color) {
    const gl = this.gl;
    const d = this.docs[k];
    if (!segs || segs.length === 0) { delete d.overlays[name]; this.dirty = true; return; }
    const o = d.overlays[name] || { buf: gl.createBuffer(), vao: gl.createVertexArray() };
    gl.bindVertexArray(o.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, o.buf);
    gl.bufferData(gl.ARRAY_BUFFER, segs, gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindVertexArray(null);
    o.count = segs.length / 3;
    o.color = color;
    d.overlays[name] = o;
    this.dirty = true;
  }

  // The marked region: a list of triangle indices.
  setRegion(k, faces) {
    const gl = this.gl;
    const d = this.docs[k];
    if (!faces || faces.length === 0) { d.region = null; this.dirty = true; return; }
    const idx = new Uint32Array(faces.length * 3);
    faces.forEach((f, i) => idx.set(d.indices.subarray(3 * f, 3 * f + 3), 3 * i));
    const r = d.region || { vao: gl.createVertexArray(), idx: gl.createBuffer() };
    gl.bindVertexArray(r.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, d.pos);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, r.idx);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.DYNAMIC_DRAW);
    gl.bindVertexArray(null);
    r.count = idx.length;
    d.region = r;
    this.dirty = true;
  }

  // A named set of triangles filled with a translucent RGBA colour over the
  // surface (the draft tool's faces below the minimum angle); null clears.
  setFaceSet(k, name, faces, color) {
    const gl = this.gl;
    const d = this.docs[k];
    d.faceSets = d.faceSets || {};
    if (!faces || faces.length === 0) { delete d.faceSets[name]; this.dirty = true; return; }
    const idx = new Uint32Array(faces.length * 3);
    faces.forEach((f, i) => idx.set(d.indices.subarray(3 * f, 3 * f + 3), 3 * i));
    const r = d.faceSets[name] || { vao: gl.createVertexArray(), idx: gl.createBuffer() };
    gl.bindVertexArray(r.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, d.pos);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, r.idx);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.DYNAMIC_DRAW);
    gl.bindVertexArray(null);
    r.count = idx.length;
    r.color = color;
    d.faceSets[name] = r;
    this.dirty = true;
  }

  wireOf(d) {
    if (d.wire) return d.wire;
    const gl = this.gl;
    const t = d.indices;
    const e = new Uint32Array(t.length * 2);
    for (let i = 0; i < t.length; i += 3) {
      e.set([t[i], t[i + 1], t[i + 1], t[i + 2], t[i + 2], t[i]], 2 * i);
    }
    const w = { vao: gl.createVertexArray(), idx: gl.createBuffer(), count: e.length };
    gl.bindVertexArray(w.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, d.pos);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, w.idx);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, e, gl.STATIC_DRAW);
    gl.bindVertexArray(null);
    d.wire = w;
    return w;
  }

  // Viewport of document k: [x, y, w, h] in device pixels.
  viewport(k) {
    const w = this.canvas.width, h = this.canvas.height;
    const n = Math.max(this.docs.length, 1);
    const cw = Math.floor(w / n);
    return [k * cw, 0, cw, h];
  }

  // The drawing buffer follows the canvas's size on the page, or
  // `fixedSize` ([w, h] device pixels) while an image is captured.
  resize() {
    const dpr = window.devicePixelRatio || 1;
    const [w, h] = this.fixedSize || [
      Math.max(1, Math.round(this.canvas.clientWidth * dpr)),
      Math.max(1, Math.round(this.canvas.clientHeight * dpr)),
    ];
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
      this.dirty = true;
    }
  }

  draw() {
    const gl = this.gl;
    this.resize();
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, this.canvas.width, this.canvas.height);
    gl.clearColor(0.16, 0.18, 0.21, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.enable(gl.SCISSOR_TEST);
    this.docs.forEach((d, k) => {
      const vp = this.viewport(k);
      gl.viewport(...vp);
      gl.scissor(...vp);
      const vpm = this.camera.viewProj(vp[2] / vp[3]);
      const shade = (vao) => {
        gl.useProgram(this.surface.p);
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D, this.colormap);
        setUniforms(gl, this.surface, Object.assign({}, this.lightUniforms ? this.lightUniforms(k) : { uMode: 0 }, {
          uViewProj: vpm,
          uEye: this.camera.eye(),
          uMinCos: d.meta.min_normal_cos,
          uThetaSamples: THETA_SAMPLES,
          uRadiusCount: this.lightUniforms ? Math.min(16, (this.lightUniforms(k).uRadii || []).length) : 0,
          uScalarOn: d.scalarOn ? 1 : 0,
          uScalarLo: d.scalarRange ? d.scalarRange.lo : 0,
          uScalarHi: d.scalarRange ? d.scalarRange.hi : 1,
          uColormap: 0,
          uBaseColor: [0.78, 0.8, 0.84],
        }));
        gl.enable(gl.POLYGON_OFFSET_FILL);
        gl.polygonOffset(1, 1);
        gl.bindVertexArray(vao);
        gl.drawElements(gl.TRIANGLES, d.count, gl.UNSIGNED_INT, 0);
        gl.disable(gl.POLYGON_OFFSET_FILL);
      };
      // the compared state left of the split (its shading only), the
      // current state with its overlays right of it
      const xs = d.compare ? vp[0] + Math.round(d.compare.split * vp[2]) : vp[0];
      if (d.compare) {
        gl.scissor(vp[0], vp[1], xs - vp[0], vp[3]);
        shade(d.compare.vao);
        gl.scissor(xs, vp[1], vp[0] + vp[2] - xs, vp[3]);
      }
      shade(d.vao);
      gl.useProgram(this.line.p);
      setUniforms(gl, this.line, { uViewProj: vpm });
      for (const set of Object.values(d.faceSets || {})) {
        gl.enable(gl.BLEND);
        gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
        gl.depthFunc(gl.LEQUAL);
        setUniforms(gl, this.line, { uColor: set.color });
        gl.bindVertexArray(set.vao);
        gl.drawElements(gl.TRIANGLES, set.count, gl.UNSIGNED_INT, 0);
        gl.depthFunc(gl.LESS);
        gl.disable(gl.BLEND);
      }
      if (d.region) {
        gl.enable(gl.BLEND);
        gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
        gl.depthFunc(gl.LEQUAL);
        setUniforms(gl, this.line, { uColor: [1.0, 0.55, 0.1, 0.35] });
        gl.bindVertexArray(d.region.vao);
        gl.drawElements(gl.TRIANGLES, d.region.count, gl.UNSIGNED_INT, 0);
        gl.depthFunc(gl.LESS);
        gl.disable(gl.BLEND);
      }
      if (this.wireframe) {
        const w = this.wireOf(d);
        setUniforms(gl, this.line, { uColor: [0.1, 0.1, 0.15, 1] });
        gl.bindVertexArray(w.vao);
        gl.drawElements(gl.LINES, w.count, gl.UNSIGNED_INT, 0);
      }
      // LEQUAL: a highlighted copy of a line (hover) drawn over the line
      // itself passes the depth test; the highlights are drawn last
      gl.depthFunc(gl.LEQUAL);
      const names = Object.keys(d.overlays).sort((a, b) => ON_TOP.has(a) - ON_TOP.has(b));
      for (const name of names) {
        const o = d.overlays[name];
        setUniforms(gl, this.line, { uColor: o.color });
        gl.bindVertexArray(o.vao);
        gl.drawArrays(gl.LINES, 0, o.count);
      }
      gl.depthFunc(gl.LESS);
      gl.bindVertexArray(null);
      if (d.compare) {
        // the divider, two device pixels wide
        gl.scissor(Math.max(vp[0], xs - 1), vp[1], 2, vp[3]);
        gl.clearColor(1.0, 0.75, 0.2, 1);
        gl.clear(gl.COLOR_BUFFER_BIT);
        gl.clearColor(0.16, 0.18, 0.21, 1);
      }
    });
    gl.disable(gl.SCISSOR_TEST);
    this.frames++;
    if (this.onFrame) this.onFrame();
  }

  // Renders `n` frames synchronously, each waited for (readPixels), while
  // `change(i)` alters the lights; returns the frame times in ms.
  timeFrames(n, change) {
    const times = [];
    const px = new Uint8Array(4);
    for (let i = 0; i < n; i++) {
      const t = performance.now();
      change(i);
      this.draw();
      this.gl.readPixels(0, 0, 1, 1, this.gl.RGBA, this.gl.UNSIGNED_BYTE, px);
      times.push(performance.now() - t);
    }
    return times;
  }

  // The pick pass of document k: every triangle drawn with its index + 1 as
  // colour (0: background) into an offscreen buffer, depth-tested, so each
  // pixel holds the nearest triangle; read back once per camera state and
  // geometry (`d.ids`), so that picking and visibility tests read memory.
  idsOf(k) {
    const gl = this.gl;
    const d = this.docs[k];
    const vp = this.viewport(k);
    const vpm = this.camera.viewProj(vp[2] / vp[3]);
    const key = vpm.concat(vp).join(',');
    if (d.ids && d.ids.key === key) return d.ids;
    if (!d.pickMesh) {
      const t = d.indices, p = d.positions;
      const e = new Float32Array(t.length * 3);
      for (let i = 0; i < t.length; i++) e.set(p.subarray(3 * t[i], 3 * t[i] + 3), 3 * i);
      const m = { vao: gl.createVertexArray(), buf: gl.createBuffer(), count: t.length };
      gl.bindVertexArray(m.vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, m.buf);
      gl.bufferData(gl.ARRAY_BUFFER, e, gl.STATIC_DRAW);
      gl.enableVertexAttribArray(0);
      gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
      gl.bindVertexArray(null);
      d.pickMesh = m;
    }
    const w = this.canvas.width, h = this.canvas.height;
    if (!this.pickFbo || this.pickFbo.w !== w || this.pickFbo.h !== h) {
      const fb = gl.createFramebuffer();
      const tex = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, w, h, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      const depth = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, w, h);
      gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
      this.pickFbo = { fb, w, h };
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.pickFbo.fb);
    gl.viewport(...vp);
    gl.disable(gl.SCISSOR_TEST);
    gl.clearColor(0, 0, 0, 0);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.useProgram(this.pick.p);
    setUniforms(gl, this.pick, { uViewProj: vpm });
    gl.bindVertexArray(d.pickMesh.vao);
    gl.drawArrays(gl.TRIANGLES, 0, d.pickMesh.count);
    gl.bindVertexArray(null);
    const data = new Uint8Array(vp[2] * vp[3] * 4);
    gl.readPixels(vp[0], vp[1], vp[2], vp[3], gl.RGBA, gl.UNSIGNED_BYTE, data);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    d.ids = { key, vp, vpm, data };
    return d.ids;
  }

  // Triangle of document k nearest to the eye at device pixel (px, py)
  // (y from the bottom), or -1.
  faceAt(k, px, py) {
    const { vp, data } = this.idsOf(k);
    const x = px - vp[0], y = py - vp[1];
    if (x < 0 || y < 0 || x >= vp[2] || y >= vp[3]) return -1;
    const i = 4 * (y * vp[2] + x);
    const id = data[i] + data[i + 1] * 256 + data[i + 2] * 65536 + data[i + 3] * 16777216;
    return id - 1;
  }

  // Triangle index under canvas pixel (x, y) (CSS pixels) and the document
  // it belongs to, or null.
  pickAt(x, y) {
    const dpr = window.devicePixelRatio || 1;
    const px = Math.round(x * dpr), py = this.canvas.height - 1 - Math.round(y * dpr);
    const k = this.docs.findIndex((_, i) => { const v = this.viewport(i); return px >= v[0] && px < v[0] + v[2]; });
    if (k < 0) return null;
    const f = this.faceAt(k, px, py);
    if (f < 0) return null;
    const d = this.docs[k];
    const t = d.indices, p = d.positions;
    const c = [0, 0, 0];
    for (let j = 0; j < 3; j++) for (let i = 0; i < 3; i++) c[i] += p[3 * t[3 * f + j] + i] / 3;
    return { doc: k, face: f, point: c };
  }

  // Whether point p of document k (its coordinates; a point on or near the
  // surface, such as a point of a highlight line) is seen from the eye: the
  // nearest triangle under p's pixel (depth-tested pick pass) must not meet
  // the eye ray through p more than `tol` (model units) before p. A point
  // on the far side of the part projects onto the part's near side and is
  // not visible; a point outside the view is not visible; a point where no
  // triangle is drawn (its silhouette pixel) is.
  isVisible(k, p, tol) {
    const vp = this.viewport(k);
    const { vpm } = this.idsOf(k);
    const m = vpm;
    const x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    const w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    if (!(w > 0)) return false;
    const px = Math.floor(vp[0] + (x / w * 0.5 + 0.5) * vp[2]);
    const py = Math.floor(vp[1] + (y / w * 0.5 + 0.5) * vp[3]);
    if (px < vp[0] || py < vp[1] || px >= vp[0] + vp[2] || py >= vp[1] + vp[3]) return false;
    const f = this.faceAt(k, px, py);
    if (f < 0) return true;
    const t = this.docs[k].indices, q = this.docs[k].positions;
    const v = (j) => [q[3 * t[3 * f + j]], q[3 * t[3 * f + j] + 1], q[3 * t[3 * f + j] + 2]];
    const [a, b, c] = [v(0), v(1), v(2)];
    const e = this.camera.eye();
    const sub = (u, z) => [u[0] - z[0], u[1] - z[1], u[2] - z[2]];
    const dot = (u, z) => u[0] * z[0] + u[1] * z[1] + u[2] * z[2];
    const ab = sub(b, a), ac = sub(c, a);
    const n = [ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]];
    const ray = sub(p, e);
    const den = dot(n, ray);
    const len = Math.hypot(...ray);
    if (!(Math.abs(den) > 1e-12 * Math.hypot(...n) * len)) return true;
    // the ray e + t·(p − e) meets the triangle's plane at t; p is at t = 1
    const hit = dot(n, sub(a, e)) / den;
    return (1 - hit) * len <= tol;
  }
}
