// Side by side: a frame over each document's part of the view, labelled
// with its name; the active document's (the one run, undo, save and the
// panels act on) is highlighted. A press in a document's part makes it
// the active one.

export class DocFrames {
  constructor(box, canvas, names, onActivate) {
    this.box = box;
    this.frames = names.map((name, k) => {
      const f = document.createElement('div');
      f.className = 'docframe';
      f.dataset.doc = String(k);
      f.style.left = `${(100 * k) / names.length}%`;
      f.style.width = `${100 / names.length}%`;
      const label = document.createElement('span');
      label.textContent = name;
      f.append(label);
      box.append(f);
      return f;
    });
    box.hidden = names.length < 2;
    // the document under the pointer, from the viewport split (viewer.js)
    canvas.addEventListener('pointerdown', (e) => {
      if (names.length < 2) return;
      const r = canvas.getBoundingClientRect();
      const k = Math.min(names.length - 1, Math.floor(((e.clientX - r.left) / r.width) * names.length));
      onActivate(k);
    }, true);
  }
  show(active) {
    this.frames.forEach((f, k) => {
      f.classList.toggle('active', k === active);
      f.querySelector('span').textContent = f.querySelector('span').textContent.replace(/ \(active\)$/, '') + (k === active ? ' (active)' : '');
    });
  }
}
