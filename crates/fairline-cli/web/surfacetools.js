// B-spline tools: the continuity of the patch boundaries drawn on the part
// (each shared edge coloured by its class: gap, G0, G1, G2; the values
// listed), the control net and the curvature combs of the isoparametric
// curves. Classes, nets and combs come from the server
// (/api/doc/K/continuity, /api/doc/K/control-net, /api/doc/K/iso-combs);
// this file only draws.
import * as api from './api.js';
import { segments } from './viewer.js';
import { $, status, showCommand } from './panels.js';

export const CLASS_COLORS = {
  gap: [0.9, 0.1, 0.1, 1],
  G0: [1.0, 0.55, 0.0, 1],
  G1: [0.25, 0.5, 1.0, 1],
  G2: [0.1, 0.8, 0.25, 1],
};
const NET_COLOR = [0.85, 0.35, 0.95, 1];
const ISO_COLOR = [0.95, 0.95, 0.3, 1];
const ISO_COMB_COLOR = [0.2, 0.85, 0.95, 1];
// The tooth of the median curvature at the comb slider's middle, as a
// share of the part's radius; the longest tooth drawn, in units of it; the
// teeth drawn per curve (the envelope goes through every sample).
const ISO_TOOTH = 0.025;
const ISO_TOOTH_CAP = 4;
const ISO_TEETH_PER_CURVE = 60;

// Segments repeated with offsets of ±`w` along each axis: lines a few
// pixels wide where WebGL draws them one pixel wide.
function thick(segs, w) {
  const out = new Float32Array(segs.length * 7);
  out.set(segs, 0);
  let o = segs.length;
  for (let a = 0; a < 3; a++) {
    for (const s of [-w, w]) {
      for (let i = 0; i < segs.length; i++) out[o + i] = segs[i] + (i % 3 === a ? s : 0);
      o += segs.length;
    }
  }
  return out;
}

const css = (c) => `rgb(${c.slice(0, 3).map((x) => Math.round(x * 255)).join(',')})`;
const fmt = (x) => Number(x).toPrecision(3);

export class SurfaceTools {
  constructor(ctx) {
    this.ctx = ctx;
    this.continuity = null; // the last answer's header, while shown
    this.net = null;
    this.iso = null; // { doc, header, data } of the shown iso-curve combs
  }

  async showContinuity(k) {
    const { viewer, state } = this.ctx;
    status('classifying patch boundaries…');
    const { header, data } = await api.frame(`/api/doc/${k}/continuity`, {});
    this.clearContinuity();
    this.continuity = header;
    this.continuityDoc = k;
    const r = 0.012 * state.session.docs[k].radius;
    for (const name of Object.keys(CLASS_COLORS)) {
      const edges = header.edges.filter((e) => e.class === name);
      const drawn = segments(edges.map((e) => ({ start: e.start, count: e.count, closed: false })), data);
      viewer.setOverlay(k, `cont-${name}`, thick(drawn, 0.002 * state.session.docs[k].radius), CLASS_COLORS[name]);
      // a cross at the worst point of every edge that is not G2
      if (name === 'G2') continue;
      const segs = [];
      const c = state.session.docs[k].center;
      for (const e of edges) {
        const p = e.worst.map((x, i) => x - c[i]);
        for (let a = 0; a < 3; a++) {
          const lo = p.slice(), hi = p.slice();
          lo[a] -= r; hi[a] += r;
          segs.push(...lo, ...hi);
        }
      }
      viewer.setOverlay(k, `cont-${name}-worst`, segs.length ? new Float32Array(segs) : null, CLASS_COLORS[name]);
    }
    this.showLegend(header);
    showCommand(header.command);
    document.body.dataset.continuity = String(header.edges.length);
    status(header.summary);
  }

  // One swatch per class with its count, then one row per edge (worst
  // first): the patches, class, gap, angle and curvature jump.
  showLegend(header) {
    const box = $('cont-legend');
    box.replaceChildren();
    for (const [name, color] of Object.entries(CLASS_COLORS)) {
      const span = document.createElement('span');
      span.className = 'swatch';
      span.dataset.class = name;
      span.style.setProperty('--swatch', css(color));
      span.textContent = `${name} (${header.classes[name] || 0})`;
      box.append(span);
    }
    const t = $('cont-edges');
    t.replaceChildren();
    const head = document.createElement('tr');
    for (const h of ['patches', 'class', 'gap', 'angle °', 'curv. %']) {
      const td = document.createElement('td'); td.textContent = h; head.append(td);
    }
    t.append(head);
    const rank = { gap: 0, G0: 1, G1: 2, G2: 3 };
    const edges = header.edges.slice().sort((a, b) => rank[a.class] - rank[b.class] || b.g1_max_deg - a.g1_max_deg);
    for (const e of edges) {
      const tr = document.createElement('tr');
      tr.dataset.class = e.class;
      const cells = [`${e.surfaces[0]} / ${e.surfaces[1]}`, e.class, fmt(e.g0_max), fmt(e.g1_max_deg), fmt(100 * e.g2_max_relative)];
      cells.forEach((v, i) => {
        const td = document.createElement('td');
        td.textContent = v;
        if (i === 1) td.style.color = css(CLASS_COLORS[e.class]);
        tr.append(td);
      });
      t.append(tr);
    }
  }

  clearContinuity() {
    const { viewer } = this.ctx;
    if (this.continuityDoc !== undefined) {
      for (const name of Object.keys(CLASS_COLORS)) {
        viewer.setOverlay(this.continuityDoc, `cont-${name}`, null);
        viewer.setOverlay(this.continuityDoc, `cont-${name}-worst`, null);
      }
    }
    this.continuity = null;
    this.continuityDoc = undefined;
    $('cont-legend').replaceChildren();
    $('cont-edges').replaceChildren();
    delete document.body.dataset.continuity;
  }

  // The control net of document k as lines, each control point a small
  // cross; `on` false removes it.
  async showNet(k, on) {
    const { viewer, state } = this.ctx;
    if (!on) {
      viewer.setOverlay(k, 'net', null);
      viewer.setOverlay(k, 'net-points', null);
      this.net = null;
      delete document.body.dataset.net;
      return;
    }
    const { header, data } = await api.frame(`/api/doc/${k}/control-net`);
    const n = header.points;
    viewer.setOverlay(k, 'net', data.slice(3 * n), NET_COLOR);
    const r = 0.006 * state.session.docs[k].radius;
    const cross = new Float32Array(18 * n);
    for (let i = 0; i < n; i++) {
      for (let a = 0; a < 3; a++) {
        const o = 18 * i + 6 * a;
        cross.set(data.subarray(3 * i, 3 * i + 3), o);
        cross.set(data.subarray(3 * i, 3 * i + 3), o + 3);
        cross[o + a] -= r; cross[o + 3 + a] += r;
      }
    }
    viewer.setOverlay(k, 'net-points', cross, [1, 1, 1, 1]);
    this.net = { doc: k, header };
    document.body.dataset.net = String(n);
    status(`control net: ${n} control points in ${header.patches.length} patch(es), ${header.segments} edges`);
  }

  // The iso-curves of document k with their curvature combs; `on` false
  // removes them.
  async showIso(k, on) {
    const { viewer } = this.ctx;
    if (!on) {
      viewer.setOverlay(k, 'iso', null);
      viewer.setOverlay(k, 'iso-comb', null);
      this.iso = null;
      delete document.body.dataset.iso;
      return;
    }
    const count = Math.max(1, Math.min(50, Math.round(Number($('iso-count').value) || 5)));
    status('combing the iso-curves…');
    const { header, data } = await api.frame(`/api/doc/${k}/iso-combs`, { count });
    this.iso = { doc: k, header, data };
    this.drawIso();
    document.body.dataset.iso = String(header.lines.length);
    status(`${header.summary}${this.isoClipped ? `; ${this.isoClipped} teeth longer than ${ISO_TOOTH_CAP}× the median curvature's cut to it (shorten the combs to see them whole)` : ''}`);
    showCommand(header.command);
  }

  // Draws the shown iso-curves and their combs: teeth (about
  // ISO_TEETH_PER_CURVE per curve), and the envelope through the ends of
  // the teeth of every sample. At the slider's middle the median curvature
  // gets a tooth of ISO_TOOTH of the part's radius; teeth
  // longer than ISO_TOOTH_CAP times that are cut to it (and counted), so
  // that the sharp places of a part neither shrink every other comb nor
  // cover the part.
  drawIso() {
    const { viewer, state } = this.ctx;
    const s = this.iso;
    if (!s) return;
    const { header, data } = s;
    const n = header.points;
    const pts = data.subarray(0, 3 * n);
    viewer.setOverlay(s.doc, 'iso', segments(header.lines, pts), ISO_COLOR);
    const ref = header.curvature_median > 0 ? header.curvature_median : header.max_curvature;
    if (!(ref > 0)) {
      viewer.setOverlay(s.doc, 'iso-comb', null);
      this.isoCombLength = 0;
      this.isoClipped = 0;
      return;
    }
    const len = ISO_TOOTH * state.session.docs[s.doc].radius * 10 ** Number($('iso-comb-scale').value);
    const scale = len / ref;
    const cap = ISO_TOOTH_CAP * len;
    this.isoCombLength = scale * header.max_curvature;
    let clipped = 0;
    const ends = new Float32Array(3 * n);
    for (let i = 0; i < n; i++) {
      const t = [0, 1, 2].map((a) => scale * data[3 * n + 3 * i + a]);
      const l = Math.hypot(t[0], t[1], t[2]);
      const f = l > cap ? cap / l : 1;
      if (f < 1) clipped++;
      for (let a = 0; a < 3; a++) ends[3 * i + a] = pts[3 * i + a] + f * t[a];
    }
    const segs = [];
    for (const l of header.lines) {
      const stride = Math.max(1, Math.floor(l.count / ISO_TEETH_PER_CURVE));
      for (let i = l.start; i < l.start + l.count; i++) {
        const last = i + 1 === l.start + l.count;
        if ((i - l.start) % stride === 0 || last) {
          segs.push(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2], ends[3 * i], ends[3 * i + 1], ends[3 * i + 2]);
        }
        if (!last) segs.push(...ends.subarray(3 * i, 3 * i + 6));
      }
    }
    this.isoClipped = clipped;
    viewer.setOverlay(s.doc, 'iso-comb', new Float32Array(segs), ISO_COMB_COLOR);
  }

  // After a step: shown results follow the current state.
  async refresh() {
    const k = this.ctx.state.active;
    if (this.continuity && this.continuityDoc === k) await this.showContinuity(k);
    if (this.net && this.net.doc === k) await this.showNet(k, true);
    if (this.iso && this.iso.doc === k) await this.showIso(k, true);
  }
}
