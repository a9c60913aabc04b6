// Light state of the page: a linear light array (DESIGN.md §5, absolute
// model coordinates) derived from the document's default array and the
// controls, and concentric circular lights on the same plane. Changing a
// control only changes shader uniforms: no server round trip.
import { cross, dot, norm } from './camera.js';

// v rotated by angle (radians) about unit axis k (Rodrigues).
function rotate(v, k, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  const kxv = cross(k, v), kv = dot(k, v);
  return [0, 1, 2].map((i) => v[i] * c + kxv[i] * s + k[i] * kv * (1 - c));
}

export class Lights {
  constructor(base, center, radius) {
    this.base = base;            // {plane_point, plane_normal, direction, spacing}
    this.center = center;        // document centre (absolute)
    this.radius = radius;
    this.spacingExp = 0;         // spacing = base spacing · 2^spacingExp
    this.directionDeg = 0;       // rotation of H about Z
    this.tiltDeg = 0;            // rotation of Z about H
    this.turnDeg = 0;            // rotation of Z about the across direction
    this.bandFraction = 0.5;     // band width / spacing
    this.lineWidth = 1.2;        // pixels
    this.sweep = 0;              // shift of the array, in spacings
    this.mode = 1;
    this.follow = 'part';
    this.radiiText = '';
  }

  spacing() { return this.base.spacing * Math.pow(2, this.spacingExp); }

  // The array {plane_point, plane_normal, direction, spacing} in absolute
  // coordinates; `camera` is used when the lights follow the view.
  array(camera) {
    let z = norm(this.base.plane_normal);
    let h = norm(this.base.direction);
    let a0 = this.base.plane_point.slice();
    if (this.follow === 'view' && camera) {
      const f = camera.frame();
      z = f.back;
      h = f.up;
      const dist = Math.hypot(a0[0] - this.center[0], a0[1] - this.center[1], a0[2] - this.center[2]);
      a0 = [0, 1, 2].map((i) => this.center[i] + camera.target[i] + z[i] * dist);
    }
    const across0 = norm(cross(z, h));
    const tilt = (this.tiltDeg * Math.PI) / 180;
    const turn = (this.turnDeg * Math.PI) / 180;
    z = norm(rotate(rotate(z, h, tilt), across0, turn));
    h = norm(rotate(rotate(h, h, tilt), across0, turn));
    h = norm(rotate(h, z, (this.directionDeg * Math.PI) / 180));
    // keep H orthogonal to Z
    const hz = dot(h, z);
    h = norm([h[0] - hz * z[0], h[1] - hz * z[1], h[2] - hz * z[2]]);
    const across = cross(z, h);
    const s = this.spacing();
    const shift = this.sweep * s;
    const point = [0, 1, 2].map((i) => a0[i] + across[i] * shift);
    return { plane_point: point, plane_normal: z, direction: h, spacing: s };
  }

  radii() {
    const typed = this.radiiText.split(',').map(Number).filter((r) => Number.isFinite(r) && r > 0);
    if (typed.length) return typed.slice(0, 16);
    // radii across the part, moved by the sweep
    const step = 0.2 * this.radius * Math.pow(2, this.spacingExp);
    return Array.from({ length: 10 }, (_, k) => (k + 1 + this.sweep) * step);
  }

  // Circular lights {center, axis, radii}: axis the light-plane normal,
  // centred 1.5 part radii above the document centre (the view centre when
  // the lights follow the view).
  circular(camera) {
    const a = this.array(camera);
    const z = a.plane_normal;
    const o = this.follow === 'view' && camera ? camera.target : [0, 0, 0];
    const c = [0, 1, 2].map((i) => this.center[i] + o[i] + z[i] * 1.5 * this.radius);
    return { center: c, axis: z, radii: this.radii() };
  }

  // Uniform values for surface.frag (positions relative to the centre).
  uniforms(camera) {
    const a = this.array(camera);
    const rel = (p) => [p[0] - this.center[0], p[1] - this.center[1], p[2] - this.center[2]];
    const c = this.circular(camera);
    const n = a.direction;
    const b = cross(c.axis, n); // n × b = axis
    // isophotes and the reflection zebra step an angle (degrees)
    const angular = this.mode === 3 || this.mode === 6;
    return {
      uMode: this.mode,
      uA0: rel(a.plane_point),
      uZ: a.plane_normal,
      uH: a.direction,
      uSpacing: angular ? 10 * Math.pow(2, this.spacingExp) : a.spacing,
      uBandHalf: this.mode === 6 ? 0.5 * this.bandFraction : 0.5 * this.bandFraction * a.spacing,
      uLineWidth: this.lineWidth,
      uCircleCenter: rel(c.center),
      uCircleN: n,
      uCircleB: b,
      uRadii: c.radii,
    };
  }
}
