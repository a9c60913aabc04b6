// Evaluation tools: the deviation map (legend, histogram, statistics
// inside and outside the marked region) and the point probe (position,
// normal, principal curvatures, the highlight distance under the current
// lights; shift-click two points for their distance). Every number comes from the server (/api/doc/K/deviation,
// /api/doc/K/probe); this file only draws.
import * as api from './api.js';
import { color, drawLegend } from './colormap.js';
import { $, status, showCommand } from './panels.js';

const fmt = (x) => (x === null || x === undefined ? '–' : Number(x).toPrecision(4));

// Draws the histogram (counts per bin over [lo, hi], centred on 0) into a
// 2-D canvas: bars coloured as the bin's centre is on the map, heights on
// a logarithmic scale, ln(1 + count), so that a few large deviations still
// show beside thousands of vertices at zero.
export function drawHistogram(canvas, hist) {
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, canvas.width, canvas.height);
  if (!hist || !hist.counts.length) return;
  const n = hist.counts.length;
  const top = Math.log1p(Math.max(1, ...hist.counts));
  const h = canvas.height - 14;
  const w = canvas.width / n;
  hist.counts.forEach((c, i) => {
    const rgb = color((i + 0.5) / n);
    g.fillStyle = `rgb(${rgb[0] * 255},${rgb[1] * 255},${rgb[2] * 255})`;
    const bh = Math.log1p(c) / top * h;
    g.fillRect(i * w, h - bh, Math.max(1, w - 1), bh);
  });
  g.fillStyle = '#dde';
  g.fillRect(canvas.width / 2, 0, 1, h);
  g.font = '10px sans-serif';
  g.fillText(Number(hist.lo).toPrecision(3), 0, canvas.height - 2);
  const hi = Number(hist.hi).toPrecision(3);
  g.fillText(hi, canvas.width - g.measureText(hi).width, canvas.height - 2);
  const mid = 'log count';
  g.fillText(mid, (canvas.width - g.measureText(mid).width) / 2, canvas.height - 2);
}

// The statistics table: one row per part (all, inside, outside).
function showStats(header) {
  const t = $('dev-stats');
  t.replaceChildren();
  const head = document.createElement('tr');
  for (const c of ['', 'max |d|', 'mean', 'rms', '95 %']) {
    const td = document.createElement('td'); td.textContent = c; head.append(td);
  }
  t.append(head);
  const rows = [['all', header.all], ['inside region', header.inside_region], ['outside region', header.outside_region],
    ['broad part', header.broad], ['local part', header.local]];
  for (const [name, s] of rows) {
    if (!s) continue;
    const tr = document.createElement('tr');
    tr.dataset.part = name;
    for (const v of [`${name} (${s.count})`, fmt(s.max_abs), fmt(s.mean), fmt(s.rms), fmt(s.p95_abs)]) {
      const td = document.createElement('td'); td.textContent = v; tr.append(td);
    }
    t.append(tr);
  }
}

// The deviation tool of the page: `ctx` gives the viewer, the state and
// the active document.
export class Tools {
  constructor(ctx) {
    this.ctx = ctx;
    this.deviation = null; // the last answer's header, while shown
    this.probes = []; // probe answers of the shift-click pair
  }

  // Fills the "against" choices (other documents when two are open).
  init(docs) {
    const sel = $('dev-against');
    if (docs.length < 2) return;
    docs.forEach((d, j) => {
      const o = document.createElement('option');
      o.value = `doc:${j}`;
      o.textContent = `document ${j + 1}: ${d.name}`;
      sel.append(o);
    });
  }

  // Computes and shows the deviation of the active document.
  async showDeviation() {
    const { viewer, state } = this.ctx;
    const k = state.active;
    const v = $('dev-against').value;
    const against = v.startsWith('doc:') ? { doc: Number(v.slice(4)) } : v;
    const show = $('dev-show').value;
    const body = { against, show };
    const faces = state.regions[k] || [];
    if (faces.length) body.faces = faces;
    status('measuring deviation…');
    const { header, data } = await api.frame(`/api/doc/${k}/deviation`, body);
    this.deviation = header;
    this.deviationDoc = k;
    viewer.setScalar(k, data, header.range);
    $('scalar').value = '';
    const part = { signed: [header.all, 'deviation'], broad: [header.broad, 'broad part of the deviation'], local: [header.local, 'local part of the deviation'] }[show];
    drawLegend($('dev-legend'), `${part[1]} (model units)`, header.range.lo, header.range.hi);
    drawHistogram($('dev-hist'), part[0].histogram);
    showStats(header);
    showCommand(header.command);
    document.body.dataset.deviation = String(header.all.max_abs);
    status(header.summary);
  }

  clearDeviation() {
    if (this.deviationDoc !== undefined) this.ctx.viewer.setScalar(this.deviationDoc, null);
    this.deviation = null;
    this.deviationDoc = undefined;
    drawLegend($('dev-legend'), '', 0, 0);
    drawHistogram($('dev-hist'), null);
    $('dev-stats').replaceChildren();
    delete document.body.dataset.deviation;
  }

  // After a step: a shown deviation follows the current state.
  async refresh() {
    if (this.deviation && this.deviationDoc === this.ctx.state.active) await this.showDeviation();
  }

  // A probe at triangle `face` of document `k` (point relative to the
  // document's centre); `pair`: keep the previous probe and measure.
  // `light`: the document's linear light array, for the highlight
  // distance under the probe (none for circular lights).
  async probe(k, face, point, pair, light) {
    const body = { face, point };
    if (light) body.light = light;
    const r = await api.json(`/api/doc/${k}/probe`, body);
    r.doc = k;
    this.probes = pair && this.probes.length === 1 ? [this.probes[0], r] : [r];
    this.showProbe();
    return r;
  }

  showProbe() {
    const { viewer, state } = this.ctx;
    const out = $('probe-out');
    const p = this.probes[this.probes.length - 1];
    if (!p) { out.textContent = ''; return; }
    const lines = [
      `point (${p.point.map((x) => x.toPrecision(5)).join(', ')})`,
      `normal (${p.normal.map((x) => x.toFixed(3)).join(', ')})`,
      `k1 ${fmt(p.k1)}  k2 ${fmt(p.k2)}`,
      `radii ${fmt(p.r1)}  ${fmt(p.r2)}`,
      `mean ${fmt(p.mean)}  Gauss ${fmt(p.gauss)}`,
    ];
    if (p.highlight) {
      const m = Math.round(p.highlight.light);
      const off = (p.highlight.light - m) * p.highlight.spacing;
      lines.push(`highlight d ${fmt(p.highlight.distance)}: light ${p.highlight.light.toFixed(2)}, ${fmt(Math.abs(off))} from line ${m}`);
    } else if ('highlight' in p) {
      lines.push('highlight: the normal is nearly parallel to the light plane here');
    }
    if (this.probes.length === 2) {
      const [a, b] = this.probes;
      const d = Math.hypot(a.point[0] - b.point[0], a.point[1] - b.point[1], a.point[2] - b.point[2]);
      lines.push(`distance ${fmt(d)} (Δ ${a.point.map((x, i) => (b.point[i] - x).toPrecision(3)).join(', ')})`);
      this.distance = d;
    } else {
      this.distance = null;
    }
    out.textContent = lines.join('\n');
    // marks, lifted off the surface along the normal: a cross and a
    // normal stick at each probe, the segment between two
    const k = p.doc;
    const c = state.session.docs[k].center;
    const r = state.session.docs[k].radius;
    const lifted = (q) => q.point.map((x, i) => x - c[i] + 0.01 * r * q.normal[i]);
    const segs = [];
    for (const q of this.probes) {
      const a = lifted(q);
      segs.push(...a, ...a.map((x, i) => x + 0.08 * r * q.normal[i]));
      for (let ax = 0; ax < 3; ax++) {
        const lo = a.slice(), hi = a.slice();
        lo[ax] -= 0.02 * r; hi[ax] += 0.02 * r;
        segs.push(...lo, ...hi);
      }
    }
    if (this.probes.length === 2) segs.push(...lifted(this.probes[0]), ...lifted(this.probes[1]));
    viewer.setOverlay(k, 'probe', new Float32Array(segs), [1, 0.85, 0.1, 1]);
  }
}
