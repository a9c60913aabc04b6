// Mouse and wheel: orbit (left drag), pan (right or shift drag), zoom
// (wheel); with a marking tool, a click or drag picks triangles instead.
export function attachControls(canvas, viewer, onPick) {
  let drag = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    drag = { x: e.clientX, y: e.clientY, button: e.button, shift: e.shiftKey, picking: false };
    if (e.button === 0 && onPick(e, 'down')) drag.picking = true;
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.picking) { onPick(e, 'move'); return; }
    if (drag.button === 2 || drag.shift) viewer.camera.pan(dx, dy, canvas.clientHeight);
    else viewer.camera.orbit(dx, dy);
    viewer.dirty = true;
  });
  canvas.addEventListener('pointerup', () => { drag = null; });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    viewer.camera.zoom(Math.exp(e.deltaY * 0.001));
    viewer.dirty = true;
  }, { passive: false });
}

// Local (canvas) coordinates of a pointer event.
export function local(canvas, e) {
  const r = canvas.getBoundingClientRect();
  return [e.clientX - r.left, e.clientY - r.top];
}
