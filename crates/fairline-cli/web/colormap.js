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
// name is empty).
export function drawLegend(canvas, name, lo, hi) {
  const g = canvas.getContext('2d');
  g.clearRect(0, 0, canvas.width, canvas.height);
  if (!name) return;
  for (let x = 0; x < canvas.width; x++) {
    const c = color(x / (canvas.width - 1));
    g.fillStyle = `rgb(${c[0] * 255},${c[1] * 255},${c[2] * 255})`;
    g.fillRect(x, 0, 1, 16);
  }
  g.fillStyle = '#dde';
  g.font = '11px sans-serif';
  g.fillText(lo.toPrecision(3), 0, 30);
  const hs = hi.toPrecision(3);
  g.fillText(hs, canvas.width - g.measureText(hs).width, 30);
  const mid = name;
  g.fillText(mid, (canvas.width - g.measureText(mid).width) / 2, 30);
}
