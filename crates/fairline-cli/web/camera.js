// Orbit camera: a target, a distance and an orientation (yaw about the up
// axis from the front toward the right, pitch above the horizontal) in the
// frame of an up axis: the part's own ('part': the up and front of the
// camera rule the server sends, the same as every `fairline` picture's),
// or z (front −y) or y (front +z); 4×4 matrices in column-major order as
// WebGL expects.
export function perspective(fovy, aspect, near, far) {
  const f = 1 / Math.tan(fovy / 2);
  const nf = 1 / (near - far);
  return [f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0];
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const norm = (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; };
export { sub, cross, dot, norm };

export function lookAt(eye, target, up) {
  const z = norm(sub(eye, target));
  const x = norm(cross(up, z));
  const y = cross(z, x);
  return [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, eye), -dot(y, eye), -dot(z, eye), 1];
}

export function multiply(a, b) {
  const o = new Array(16).fill(0);
  for (let c = 0; c < 4; c++) for (let r = 0; r < 4; r++) {
    let s = 0;
    for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
    o[c * 4 + r] = s;
  }
  return o;
}

export class Camera {
  constructor() {
    this.up = 'z';
    this.part = { up: [0, 0, 1], front: [0, -1, 0] };
    this.iso = [0.61, 0.44];
    this.yaw = this.iso[0];
    this.pitch = this.iso[1];
    this.distance = 3;
    this.target = [0, 0, 0];
    this.radius = 1;
  }
  // Takes the part's view (`view` of the session: unit `view_dir` from the eye
  // toward the part, `up`, horizontal `front`) as the 'part' frame and the
  // iso view, and looks from it.
  setPartView(view) {
    if (!view) return;
    const up = norm(view.up), front = norm(view.front), right = cross(up, front);
    const e = norm(view.view_dir.map((c) => -c));
    this.part = { up, front };
    this.iso = [Math.atan2(dot(e, right), dot(e, front)), Math.asin(Math.max(-1, Math.min(1, dot(e, up))))];
    this.up = 'part';
    this.standard('iso');
  }
  upVector() {
    if (this.up === 'part') return this.part.up;
    return this.up === 'z' ? [0, 0, 1] : [0, 1, 0];
  }
  frontVector() {
    if (this.up === 'part') return this.part.front;
    return this.up === 'z' ? [0, -1, 0] : [0, 0, 1];
  }
  // unit vector from the target to the eye:
  // cos(pitch)·(cos(yaw)·front + sin(yaw)·(up × front)) + sin(pitch)·up
  direction() {
    const cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    const cy = Math.cos(this.yaw), sy = Math.sin(this.yaw);
    const up = this.upVector(), front = this.frontVector(), right = cross(up, front);
    return [0, 1, 2].map((i) => cp * (cy * front[i] + sy * right[i]) + sp * up[i]);
  }
  eye() {
    const d = this.direction();
    return [this.target[0] + d[0] * this.distance, this.target[1] + d[1] * this.distance, this.target[2] + d[2] * this.distance];
  }
  // camera frame: right and up vectors in model space
  frame() {
    const z = this.direction();
    let x = cross(this.upVector(), z);
    if (Math.hypot(...x) < 1e-9) x = [1, 0, 0];
    x = norm(x);
    return { right: x, up: cross(z, x), back: z };
  }
  viewProj(aspect) {
    const { up } = this.frame();
    const proj = perspective(0.6, aspect, this.distance * 0.01 + 1e-9, this.distance + 4 * this.radius);
    return multiply(proj, lookAt(this.eye(), this.target, up));
  }
  fit(radius) {
    this.radius = radius;
    this.target = [0, 0, 0];
    this.distance = radius / Math.sin(0.3) * 1.05;
  }
  orbit(dx, dy) {
    this.yaw -= dx * 0.008;
    this.pitch = Math.max(-1.55, Math.min(1.55, this.pitch + dy * 0.008));
  }
  pan(dx, dy, height) {
    const { right, up } = this.frame();
    const s = (2 * this.distance * Math.tan(0.3)) / height;
    for (let i = 0; i < 3; i++) this.target[i] += (-dx * right[i] + dy * up[i]) * s;
  }
  zoom(factor) { this.distance = Math.max(1e-6 * this.radius, this.distance * factor); }
  standard(name) {
    const views = { front: [0, 0], back: [Math.PI, 0], right: [Math.PI / 2, 0], left: [-Math.PI / 2, 0], top: [0, 1.55], bottom: [0, -1.55], iso: this.iso };
    const v = views[name] || views.iso;
    this.yaw = v[0];
    this.pitch = v[1];
  }
}
