// Saved views: named cameras (up axis, orientation, target, distance) kept
// in the browser's localStorage under the names of the open files, listed
// with a click to restore and a button to forget.

const FIELDS = ['up', 'yaw', 'pitch', 'distance', 'target'];

export class SavedViews {
  constructor(list, viewer, fileNames, onRestore) {
    this.list = list;
    this.viewer = viewer;
    this.key = `fairline.views:${fileNames.join('|')}`;
    this.onRestore = onRestore;
    this.render();
  }
  all() {
    try { return JSON.parse(localStorage.getItem(this.key)) || []; } catch { return []; }
  }
  store(views) {
    localStorage.setItem(this.key, JSON.stringify(views));
    this.render();
  }
  // Saves the current camera as `name` (replacing a view of that name).
  save(name) {
    const c = this.viewer.camera;
    const view = { name };
    for (const f of FIELDS) view[f] = Array.isArray(c[f]) ? c[f].slice() : c[f];
    this.store([...this.all().filter((v) => v.name !== name), view]);
  }
  restore(name) {
    const v = this.all().find((x) => x.name === name);
    if (!v) return false;
    const c = this.viewer.camera;
    for (const f of FIELDS) c[f] = Array.isArray(v[f]) ? v[f].slice() : v[f];
    this.viewer.dirty = true;
    this.onRestore(v);
    return true;
  }
  remove(name) { this.store(this.all().filter((v) => v.name !== name)); }
  render() {
    const items = this.all().map((v) => {
      const li = document.createElement('li');
      const go = document.createElement('button');
      go.textContent = v.name;
      go.className = 'view-restore';
      go.title = `Restore the view “${v.name}”`;
      go.addEventListener('click', () => this.restore(v.name));
      const del = document.createElement('button');
      del.textContent = '×';
      del.className = 'view-delete';
      del.title = `Forget the view “${v.name}”`;
      del.addEventListener('click', () => this.remove(v.name));
      li.append(go, del);
      return li;
    });
    this.list.replaceChildren(...items);
  }
}
