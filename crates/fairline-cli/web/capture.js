// Image capture: the current view (every document, lights, overlays)
// rendered once at a chosen size in pixels, as a PNG blob. The camera and
// the aspect of each document's part follow the asked size, so a wide
// image shows more to the sides rather than a stretched view.

export async function capture(viewer, width, height) {
  const gl = viewer.gl;
  const dims = gl.getParameter(gl.MAX_VIEWPORT_DIMS);
  const max = Math.min(dims[0], dims[1], gl.getParameter(gl.MAX_RENDERBUFFER_SIZE));
  const w = Math.round(width), h = Math.round(height);
  if (!(w >= 16 && h >= 16 && w <= max && h <= max)) {
    throw new Error(`image size must be between 16 and ${max} pixels on each side`);
  }
  viewer.fixedSize = [w, h];
  try {
    viewer.draw();
    // the copy is taken when toBlob is called, before the next frame
    return await new Promise((resolve, reject) => viewer.canvas.toBlob((b) => (b ? resolve(b) : reject(new Error('the image could not be encoded'))), 'image/png'));
  } finally {
    viewer.fixedSize = null;
    viewer.dirty = true;
  }
}
