// Session files: the page's view (camera, light controls, marks, active
// document) collected for the server, which adds the files and the
// history positions and writes the JSON (/api/session-file); and a
// session's view applied to the page, when the server opened one
// (`fairline view --session FILE`) or a file is chosen with "open session".
import * as api from './api.js';
import { $, status, showCommand } from './panels.js';

// The page controls a session keeps (the light array's, the view's and the
// evaluation tools').
const CONTROLS = ['up', 'mode', 'follow', 'spacing', 'direction', 'tilt', 'turn', 'band', 'linewidth', 'sweep', 'radii', 'wireframe',
  'sec-normal', 'sec-count', 'sec-spacing', 'sec-comb', 'sec-comb-scale', 'dev-against', 'dev-show', 'draft-pull', 'draft-min',
  'iso-count', 'iso-comb-scale'];

export class Session {
  // `ctx`: viewer, state, the evaluation tools (`tools`: deviation,
  // `shape`: sections and draft, `surfaceTools`: iso combs), and
  // `setRegion(k, faces)`, `jumpTo(k, cursor)` callbacks of the page.
  constructor(ctx) {
    this.ctx = ctx;
  }

  // The view part of a session: plain JSON.
  collect() {
    const { viewer, state } = this.ctx;
    const c = viewer.camera;
    const controls = {};
    for (const id of CONTROLS) controls[id] = $(id).type === 'checkbox' ? $(id).checked : $(id).value;
    return {
      active: state.active,
      names: state.session.docs.map((d) => d.name),
      camera: { up: c.up, yaw: c.yaw, pitch: c.pitch, distance: c.distance, target: c.target.slice() },
      controls,
      marks: state.session.docs.map((_, k) => state.regions[k] || []),
      tools: this.collectTools(),
    };
  }

  // Which evaluation overlays are shown, on which document: the sections
  // (through their picked point), the deviation map, the draft map, the
  // iso combs. Their settings are controls (CONTROLS).
  collectTools() {
    const { tools, shape, surfaceTools } = this.ctx;
    const out = {};
    if (shape && shape.section) out.section = { doc: shape.section.doc, point: shape.section.point.slice() };
    if (tools && tools.deviation) out.deviation = { doc: tools.deviationDoc };
    if (shape && shape.draft) out.draft = { doc: shape.draftDoc };
    if (surfaceTools && surfaceTools.iso) out.iso = { doc: surfaceTools.iso.doc };
    return out;
  }

  // Shows again the overlays `collectTools` recorded (after the controls,
  // history and marks are restored); an entry naming no open document, or
  // iso combs on a mesh, is left out.
  async applyTools(saved) {
    const { tools, shape, surfaceTools, state } = this.ctx;
    if (!saved || typeof saved !== 'object') return;
    const docs = state.session.docs;
    const doc = (e) => (e && Number.isInteger(e.doc) && e.doc >= 0 && e.doc < docs.length ? e.doc : null);
    const s = saved.section;
    if (shape && doc(s) !== null && Array.isArray(s.point) && s.point.length === 3 && s.point.every(Number.isFinite)) {
      await shape.cut(doc(s), s.point.map(Number));
    }
    if (surfaceTools && doc(saved.iso) !== null && docs[doc(saved.iso)].kind === 'surface') {
      $('iso-combs').checked = true;
      await surfaceTools.showIso(doc(saved.iso), true);
    }
    // a colour map: the deviation or the draft of the document shown active
    if (shape && doc(saved.draft) !== null) {
      this.ctx.activate(doc(saved.draft));
      await shape.showDraft();
    } else if (tools && doc(saved.deviation) !== null) {
      this.ctx.activate(doc(saved.deviation));
      await tools.showDeviation();
    }
  }

  // Saves the session into the save folder under the name in the Files
  // panel (default: the first file's stem + "-session.json").
  async save() {
    const { state } = this.ctx;
    const given = $('session-name').value.trim();
    const name = given || `${state.session.docs[0].name.replace(/\.[^.]*$/, '')}-session.json`;
    const r = await api.json('/api/session-file', { name, view: this.collect() });
    this.saved = r;
    showCommand(r.command);
    status(`session saved as ${r.path}${r.states.length ? ` with ${r.states.length} state file(s)` : ''}`);
    return r;
  }

  // Applies a session's view; `documents` (the history positions) are
  // applied when the history has the same steps up to them.
  async apply(view, documents) {
    const { viewer, state } = this.ctx;
    if (!view || typeof view !== 'object') return;
    const names = state.session.docs.map((d) => d.name);
    if (view.names && view.names.join('|') !== names.join('|')) {
      status(`this session is of ${view.names.join(' and ')}; open it with fairline view --session FILE`, true);
      return;
    }
    for (const [id, v] of Object.entries(view.controls || {})) {
      const el = $(id);
      if (!el || !CONTROLS.includes(id)) continue;
      if (el.type === 'checkbox') el.checked = Boolean(v); else el.value = String(v);
      // the page listens to `input` on sliders and lists, `change` on the rest
      el.dispatchEvent(new Event('input'));
      el.dispatchEvent(new Event('change'));
    }
    const c = view.camera;
    if (c && [c.yaw, c.pitch, c.distance].every(Number.isFinite) && Array.isArray(c.target) && c.target.length === 3) {
      viewer.camera.up = c.up === 'y' ? 'y' : 'z';
      viewer.camera.yaw = c.yaw;
      viewer.camera.pitch = c.pitch;
      viewer.camera.distance = Math.max(c.distance, 1e-9);
      viewer.camera.target = c.target.map(Number);
    }
    if (documents) {
      for (let k = 0; k < documents.length && k < names.length; k++) await this.ctx.jumpTo(k, documents[k].cursor, documents[k].steps);
    }
    (view.marks || []).forEach((faces, k) => {
      const n = state.session.docs[k] ? state.session.docs[k].triangles : 0;
      if (Array.isArray(faces)) this.ctx.setRegion(k, faces.filter((f) => Number.isInteger(f) && f >= 0 && f < n));
    });
    await this.applyTools(view.tools);
    if (Number.isInteger(view.active) && view.active < names.length) this.ctx.activate(view.active);
    viewer.dirty = true;
    document.body.dataset.sessionApplied = '1';
  }

  // A session file chosen in the page.
  async open(file) {
    const s = JSON.parse(await file.text());
    if (s.fairline_session !== 1) throw new Error(`${file.name}: not a fairline session (format 1)`);
    await this.apply(s.view, s.documents);
    status(`session ${file.name} applied`);
  }
}
