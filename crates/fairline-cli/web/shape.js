// Shape tools: plane sections with curvature combs (the "section" tool of
// the Mark panel and the Section panel) and the draft-angle map (Draft
// panel). Sections and angles come from the server (/api/doc/K/section,
// /api/doc/K/draft); this file only draws them.
import * as api from './api.js';
import { drawLegend } from './colormap.js';
import { segments } from './viewer.js';
import { $, status, showCommand, showReport } from './panels.js';

const SECTION_COLOR = [0.15, 0.95, 0.35, 1];
const COMB_COLOR = [0.95, 0.3, 0.85, 1];
const BELOW_COLOR = [1.0, 0.85, 0.0, 0.6];

// Unit vector of a direction choice: "x", "-z", "0,0,1" or "view" (from
// the target towards the eye: the direction the viewer looks along,
// reversed, so that a pull "towards the viewer" reads as positive draft).
export function direction(choice, camera) {
  if (choice === 'view') {
    const e = camera.eye(), t = camera.target;
    const d = [e[0] - t[0], e[1] - t[1], e[2] - t[2]];
    const l = Math.hypot(...d) || 1;
    return d.map((x) => x / l);
  }
  const axes = { x: [1, 0, 0], y: [0, 1, 0], z: [0, 0, 1] };
  if (axes[choice]) return axes[choice];
  if (choice.startsWith('-') && axes[choice.slice(1)]) return axes[choice.slice(1)].map((x) => -x);
  return choice.split(',').map(Number);
}

export class ShapeTools {
  constructor(ctx) {
    this.ctx = ctx;
    this.section = null; // { doc, point, header, data } of the last section
    this.draft = null; // the last draft answer's header, while shown
  }

  // Sections of document k through `point` (relative to its centre) with
  // the Section panel's normal, plane count and spacing.
  async cut(k, point) {
    const { viewer, state } = this.ctx;
    const d = state.session.docs[k];
    const normal = direction($('sec-normal').value, viewer.camera);
    const count = Math.max(1, Math.min(200, Math.round(Number($('sec-count').value) || 1)));
    const given = Number($('sec-spacing').value);
    const spacing = $('sec-spacing').value.trim() && Number.isFinite(given) ? given : 0.1 * d.radius;
    // the planes are centred on the picked point
    const first = point.map((x, i) => x - 0.5 * (count - 1) * spacing * normal[i]);
    status('cutting sections…');
    const { header, data } = await api.frame(`/api/doc/${k}/section`, { point: first, normal, count, spacing, comb_scale: this.combScale(d, 1) });
    this.section = { doc: k, point, header, data };
    this.drawSection();
    showCommand(header.command);
    showReport(header.report);
    $('sec-out').textContent = `${header.lines.length} curve(s) on ${count} plane(s), ${header.points} points; largest curvature ${Number(header.max_curvature).toPrecision(3)}`;
    document.body.dataset.sections = String(header.lines.length);
    status(header.summary);
  }

  // Comb length per unit curvature: the slider gives the length of the
  // largest tooth as a fraction of the part's radius (logarithmic).
  combScale(doc, kmax) {
    const len = 0.15 * doc.radius * 10 ** Number($('sec-comb-scale').value);
    return kmax > 0 ? len / kmax : 0;
  }

  drawSection() {
    const { viewer, state } = this.ctx;
    const s = this.section;
    if (!s) return;
    const { header, data } = s;
    const n = header.points;
    const pts = data.subarray(0, 3 * n);
    viewer.setOverlay(s.doc, 'section', segments(header.lines, pts), SECTION_COLOR);
    if (!$('sec-comb').checked || !(header.max_curvature > 0)) {
      viewer.setOverlay(s.doc, 'comb', null);
      this.combLength = 0;
      return;
    }
    const scale = this.combScale(state.session.docs[s.doc], header.max_curvature);
    this.combLength = scale * header.max_curvature;
    // teeth from each point to its comb end, and the envelope through the ends
    const segs = [];
    for (const l of header.lines) {
      const end = (i) => [0, 1, 2].map((a) => pts[3 * i + a] + scale * data[3 * n + 3 * i + a]);
      for (let i = l.start; i < l.start + l.count; i++) {
        segs.push(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2], ...end(i));
        const last = i + 1 === l.start + l.count;
        if (!last || l.closed) segs.push(...end(i), ...end(last ? l.start : i + 1));
      }
    }
    viewer.setOverlay(s.doc, 'comb', new Float32Array(segs), COMB_COLOR);
  }

  clearSection() {
    if (this.section) {
      this.ctx.viewer.setOverlay(this.section.doc, 'section', null);
      this.ctx.viewer.setOverlay(this.section.doc, 'comb', null);
    }
    this.section = null;
    $('sec-out').textContent = '';
    delete document.body.dataset.sections;
  }

  // After a step: shown sections follow the current state.
  async refresh() {
    if (this.section && this.section.doc === this.ctx.state.active) await this.cut(this.section.doc, this.section.point);
    if (this.draft && this.draftDoc === this.ctx.state.active) await this.showDraft();
  }

  // The draft-angle map of the active document against the Draft panel's
  // pull direction; faces below the minimum angle filled in yellow.
  async showDraft() {
    const { viewer, state } = this.ctx;
    const k = state.active;
    const pull = direction($('draft-pull').value, viewer.camera);
    const minAngle = Number($('draft-min').value);
    status('measuring draft angles…');
    const { header, data } = await api.frame(`/api/doc/${k}/draft`, { pull, min_angle: minAngle });
    this.draft = header;
    this.draftDoc = k;
    viewer.setScalar(k, data, header.range);
    viewer.setFaceSet(k, 'draft-below', header.below, BELOW_COLOR);
    $('scalar').value = '';
    this.drawDraftLegend(header);
    showCommand(header.command);
    showReport(header.report);
    const r = header.report;
    $('draft-out').textContent = `below ${r.min_angle_deg}°: ${(100 * r.below_share).toFixed(2)} % of the area (${r.faces_below} of ${r.faces} triangles); positive ${(100 * r.positive_share).toFixed(1)} %, negative ${(100 * r.negative_share).toFixed(1)} %`;
    document.body.dataset.draft = String(r.below_share);
    status(header.summary);
  }

  // The colour bar over [−90°, 90°] with the band |draft| < min marked by
  // two ticks, and the yellow swatch of the faces below the minimum.
  drawDraftLegend(header) {
    const c = $('draft-legend');
    drawLegend(c, 'draft angle (°)', -90, 90);
    const g = c.getContext('2d');
    const m = header.report.min_angle_deg;
    g.fillStyle = '#000';
    for (const a of [-m, m]) g.fillRect(Math.round((a + 90) / 180 * (c.width - 1)), 0, 1, 16);
    g.fillStyle = `rgb(${BELOW_COLOR.slice(0, 3).map((x) => x * 255).join(',')})`;
    g.fillRect(0, 38, 28, 10);
    g.fillStyle = '#dde';
    g.font = '11px sans-serif';
    g.fillText(`|draft| < ${m}°: ${(100 * header.report.below_share).toFixed(1)} % of the area`, 34, 47);
  }

  clearDraft() {
    if (this.draftDoc !== undefined) {
      this.ctx.viewer.setScalar(this.draftDoc, null);
      this.ctx.viewer.setFaceSet(this.draftDoc, 'draft-below', null);
    }
    this.draft = null;
    this.draftDoc = undefined;
    const c = $('draft-legend');
    c.getContext('2d').clearRect(0, 0, c.width, c.height);
    $('draft-out').textContent = '';
    delete document.body.dataset.draft;
  }
}
