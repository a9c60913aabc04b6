// Colour map (a perceptually ordered blue–white–red diverging map, suited
// to signed curvature) as a 256×1 texture, and its legend.
export function color(t) {
  const stops = [[0, [0.23, 0.30, 0.75]], [0.5, [0.87, 0.87, 0.87]], [1, [0.71, 0.02, 0.15]]];
  for (let i = 1; i < stops.length; i++) {
    if (t <= stops[i][0]) {
      const [t0, a] = stops[i - 1], [t1, b] = stops[i];
      const u = (t - t0) / (t1 - t0);
      return a.map((x, j) => x + (b[j] - x) * u);
    }
  }
  return stops[stops.length - 1][1];
}

export function colormapTexture(gl) {
  const data = new Uint8Array(256 * 4);
  for (let i = 0; i < 256; i++) {
    const c = color(i / 255);
    data.set([c[0] * 255, c[1] * 255, c[2] * 255, 255], 4 * i);
  }
  const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, 256, 1, 0, gl.RGBA, gl.UNSIGNED_BYTE, data);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  return tex;
}

// Draws the legend of `name` over [lo, hi] into a 2-D canvas (cleared when
// name is empty): the bar, the range at its ends (and 0 at the middle of a
// range centred on 0, as the server's rule makes it for signed fields),
// and, when values lie beyond the range (`clipped`), arrowheads at the
// ends and the words "values beyond: clipped".
export function drawLegend(canvas, name, lo, hi, clipped = false) {
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, canvas.width, canvas.height);
  canvas.dataset.range = name ? `${lo},${hi}` : '';
  canvas.dataset.clipped = name && clipped ? '1' : '';
  if (!name) return;
  const tip = clipped ? 8 : 0;
  const w = canvas.width - 2 * tip;
  for (let x = 0; x < w; x++) {
    const c = color(x / (w - 1));
    g.fillStyle = `rgb(${c[0] * 255},${c[1] * 255},${c[2] * 255})`;
    g.fillRect(tip + x, 0, 1, 16);
  }
  if (clipped) {
    for (const [x0, x1, t] of [[tip, 0, 0], [canvas.width - tip, canvas.width, 1]]) {
      const c = color(t);
      g.fillStyle = `rgb(${c[0] * 255},${c[1] * 255},${c[2] * 255})`;
      g.beginPath(); g.moveTo(x0, 0); g.lineTo(x1, 8); g.lineTo(x0, 16); g.closePath(); g.fill();
    }
  }
  g.fillStyle = '#dde';
  g.font = '11px sans-serif';
  const ls = lo.toPrecision(3);
  g.fillText(ls, tip, 30);
  const hs = hi.toPrecision(3);
  g.fillText(hs, canvas.width - tip - g.measureText(hs).width, 30);
  // the name between the end values where it fits, else under them (or,
  // on a legend too short for a second line, as much of it as fits)
  const room = canvas.width - 2 * tip - g.measureText(ls).width - g.measureText(hs).width - 16;
  const centred = Math.abs(lo + hi) <= 1e-9 * Math.abs(hi - lo);
  let mid = centred ? `${name} (0 at the middle)` : name;
  let y = 30;
  if (g.measureText(mid).width > room) {
    if (canvas.height >= 44) {
      y = 43;
    } else {
      mid = name;
      while (mid.length > 1 && g.measureText(`${mid}…`).width > room) mid = mid.slice(0, -1);
      if (mid !== name) mid = `${mid}…`;
    }
  }
  g.fillText(mid, (canvas.width - g.measureText(mid).width) / 2, y);
  if (clipped && canvas.height >= y + 14) {
    const note = 'values beyond: clipped';
    g.fillText(note, (canvas.width - g.measureText(note).width) / 2, y + 13);
  }
}
