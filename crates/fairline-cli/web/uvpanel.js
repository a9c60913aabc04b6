// The (u, v) panel of a B-spline patch: the pre-images of the circular
// highlight lines computed by the library, coloured by radius with a
// legend. Linked both ways with the 3-D view: hovering a line in either view
// lights it up in both (`setHover`); two clicks on a line in either view
// (`pick`: line and point index, the same in both views) pick the endpoints
// of a stretch to fair (DESIGN.md §5 endpoints, snapped by the library to
// the pre-image).
export const PALETTE = ['#e6194b', '#3cb44b', '#4363d8', '#f58231', '#911eb4', '#46f0f0', '#f032e6', '#bcf60c', '#fabebe', '#008080', '#e6beff', '#9a6324', '#fffac8', '#800000', '#aaffc3', '#808000'];

export function rgba(hex) {
  const n = parseInt(hex.slice(1), 16);
  return [((n >> 16) & 255) / 255, ((n >> 8) & 255) / 255, (n & 255) / 255, 1];
}

export class UvPanel {
  constructor(canvas, onHover, onEndpoints) {
    this.canvas = canvas;
    this.lines = [];          // {radius, light, closed, uv: Float32Array}
    this.domain = [[0, 1], [0, 1]];
    this.hover = -1;
    this.pending = null;      // first endpoint {radius, uv}
    this.endpoints = [];      // [{radius, start, end}]
    this.marks = [];          // 3-D points of the picks (pending last)
    this.point3 = () => null; // (line, k) → 3-D point, set by the page
    this.onHover = onHover;
    this.onEndpoints = onEndpoints;
    canvas.addEventListener('mousemove', (e) => this.move(e));
    canvas.addEventListener('click', (e) => this.click(e));
  }

  set(header, data) {
    this.domain = header.domain;
    const uv0 = header.uv_offset;
    this.lines = header.lines.filter((l) => l.kind === 'line').map((l) => ({
      radius: l.radius, light: l.light, closed: l.closed, start: l.start, count: l.count,
      uv: data.subarray(uv0 + 2 * l.uv_start, uv0 + 2 * (l.uv_start + l.count)),
    }));
    this.hover = -1;
    this.draw();
  }

  toPx(u, v) {
    const [[u0, u1], [v0, v1]] = this.domain;
    const m = 12, w = this.canvas.width - 2 * m, h = this.canvas.height - 2 * m;
    return [m + ((u - u0) / (u1 - u0 || 1)) * w, m + (1 - (v - v0) / (v1 - v0 || 1)) * h];
  }

  // nearest line point to canvas pixel (x, y): {line, k, dist}
  nearest(x, y) {
    let best = { line: -1, k: -1, dist: Infinity };
    this.lines.forEach((l, i) => {
      for (let k = 0; k < l.count; k++) {
        const [px, py] = this.toPx(l.uv[2 * k], l.uv[2 * k + 1]);
        const d = Math.hypot(px - x, py - y);
        if (d < best.dist) best = { line: i, k, dist: d };
      }
    });
    return best;
  }

  pos(e) {
    const r = this.canvas.getBoundingClientRect();
    return [(e.clientX - r.left) * (this.canvas.width / r.width), (e.clientY - r.top) * (this.canvas.height / r.height)];
  }

  move(e) {
    const n = this.nearest(...this.pos(e));
    this.setHover(n.dist < 8 ? n.line : -1);
  }

  // Lights up line h (-1: none) here and, through onHover, in the 3-D view.
  setHover(h) {
    if (h !== this.hover) {
      this.hover = h;
      this.draw();
      this.onHover(h >= 0 ? this.lines[h] : null);
    }
  }

  click(e) {
    const n = this.nearest(...this.pos(e));
    if (n.dist > 8) return;
    this.pick(n.line, n.k);
  }

  // Picks point k of line i as an endpoint: the first pick of a radius is
  // pending, the second one closes the stretch.
  pick(i, k) {
    const l = this.lines[i];
    if (!l || k < 0 || k >= l.count) return;
    const uv = [l.uv[2 * k], l.uv[2 * k + 1]];
    if (!this.pending || this.pending.radius !== l.radius) {
      if (this.pending) this.marks.pop();
      this.pending = { radius: l.radius, uv };
    } else {
      this.endpoints.push({ radius: l.radius, start: this.pending.uv, end: uv });
      this.pending = null;
    }
    this.marks.push(this.point3(i, k));
    this.draw();
    this.onEndpoints(this.endpoints);
  }

  clearEndpoints() {
    this.endpoints = [];
    this.marks = [];
    this.pending = null;
    this.draw();
    this.onEndpoints(this.endpoints);
  }

  draw() {
    const g = this.canvas.getContext('2d');
    g.fillStyle = '#15181c';
    g.fillRect(0, 0, this.canvas.width, this.canvas.height);
    g.strokeStyle = '#556';
    const [a, b] = [this.toPx(this.domain[0][0], this.domain[1][0]), this.toPx(this.domain[0][1], this.domain[1][1])];
    g.strokeRect(a[0], b[1], b[0] - a[0], a[1] - b[1]);
    const radii = [...new Set(this.lines.map((l) => l.radius))];
    this.lines.forEach((l, i) => {
      g.strokeStyle = PALETTE[l.light % PALETTE.length];
      g.lineWidth = i === this.hover ? 3.5 : 1.2;
      g.beginPath();
      for (let k = 0; k < l.count; k++) {
        const [x, y] = this.toPx(l.uv[2 * k], l.uv[2 * k + 1]);
        if (k === 0) g.moveTo(x, y); else g.lineTo(x, y);
      }
      if (l.closed) g.closePath();
      g.stroke();
    });
    g.fillStyle = '#ff0';
    const dot = (uv) => { const [x, y] = this.toPx(uv[0], uv[1]); g.beginPath(); g.arc(x, y, 4, 0, 7); g.fill(); };
    for (const e of this.endpoints) { dot(e.start); dot(e.end); }
    if (this.pending) dot(this.pending.uv);
    // legend of radii
    g.font = '10px sans-serif';
    radii.forEach((r, i) => {
      const l = this.lines.find((x) => x.radius === r);
      g.fillStyle = PALETTE[l.light % PALETTE.length];
      g.fillText(`R=${Number(r).toPrecision(3)}`, 4 + 52 * (i % 5), this.canvas.height - 2 - 11 * Math.floor(i / 5));
    });
  }
}
