// The workbench page: loads the session, draws the documents, wires the
// controls. Everything computed comes from the API; JavaScript only shades.
import * as api from './api.js';
import { Viewer, segments } from './viewer.js';
import { Lights } from './lights.js';
import { attachControls, local } from './picking.js';
import { drawLegend } from './colormap.js';
import { UvPanel, PALETTE, rgba } from './uvpanel.js';
import { $, status, showCommand, showReport, showHistory, offer, offerJson } from './panels.js';
import { Tools } from './tools.js';
import { installShortcuts } from './shortcuts.js';
import { Help } from './help.js';
import { DocFrames } from './docframes.js';
import { capture } from './capture.js';
import { SavedViews } from './views.js';
import { ShapeTools } from './shape.js';
import { SurfaceTools } from './surfacetools.js';
import { Session } from './session.js';

const state = { labels: [], surfaceDoc: -1, uvData: null, uvCircular: null, session: null, active: 0, regions: [], detected: [], before: false, job: null, lastDownload: null, shown: { lines: false, detect: false } };
window.fairline = { state };

const viewer = new Viewer($('gl'));
const tools = new Tools({ viewer, state });
window.fairline.tools = tools;
const shape = window.fairline.shape = new ShapeTools({ viewer, state });
const surfaceTools = window.fairline.surfaceTools = new SurfaceTools({ viewer, state });
const sessionFile = window.fairline.session = new Session({ viewer, state, tools, shape, surfaceTools, setRegion: (k, faces) => setRegionOf(k, faces), jumpTo: (k, c, steps) => jumpDoc(k, c, steps), activate: (k) => activate(k) });
let lights = [];
let frames = null;

function activeDoc() { return state.session.docs[state.active]; }

// Positions, normals (and the first time the triangles) of document k, all
// requested at once; `early` holds requests already under way.
async function loadGeometry(k, step, early) {
  const d = state.session.docs[k];
  const [p, n, idx] = await Promise.all(early || [
    api.positions(k, step),
    api.normals(k, step),
    viewer.docs[k] ? viewer.docs[k].indices : api.indices(k),
  ]);
  mark('geometry');
  viewer.setGeometry(k, d, p, n, idx);
  mark('upload');
}

// Milliseconds since the navigation started at each stage of the first
// frame (window.fairline.timeline; the benchmark prints it).
const timeline = {};
function mark(name) { if (!(name in timeline)) timeline[name] = Math.round(performance.now()); }

async function refreshSession() {
  state.session = await api.session();
  showSession();
}

// History, report, command and save folder of the active document.
function showSession() {
  const d = activeDoc();
  showHistory(d.history, guard(jumpTo));
  if (frames) frames.show(state.active);
  const step = d.history.steps[d.history.cursor];
  showReport(step.report);
  showCommand(step.command);
  $('save-dir').textContent = `saves go to ${state.session.save_dir}`;
}

// The history step the page shows: the one before the current step while
// "before" is on, else the current one (undefined).
function shownStep() {
  const d = activeDoc();
  return state.before && d.history.cursor > 0 ? d.history.cursor - 1 : undefined;
}

async function reloadActive() {
  await refreshSession();
  const d = activeDoc();
  const step = shownStep();
  await loadGeometry(state.active, step);
  if (d.kind === 'surface') await loadOutlines(state.active, step);
  await applyScalar();
  await tools.refresh();
  await shape.refresh();
  await surfaceTools.refresh();
  await showCompare();
  viewer.setOverlay(state.active, 'lines', null);
  viewer.setOverlay(state.active, 'stretches', null);
  state.shown = { lines: false, detect: false };
}

// The before/after divider: the state before the current step is drawn
// left of it, the current state (with its overlays) right of it; on the
// active document only.
async function showCompare() {
  const k = state.active;
  const d = activeDoc();
  viewer.docs.forEach((_, j) => { if (j !== k) viewer.setCompare(j, null); });
  if (!$('compare').checked || d.history.cursor === 0) {
    viewer.setCompare(k, null);
    delete document.body.dataset.compare;
    if ($('compare').checked) status('compare: no step yet on this document');
    return;
  }
  const step = d.history.cursor - 1;
  const [p, n] = await Promise.all([api.positions(k, step), api.normals(k, step)]);
  viewer.setCompare(k, p, n, Number($('split').value));
  document.body.dataset.compare = String(step);
  status(`compare: left of the divider the state before "${d.history.steps[d.history.cursor].label}", right of it the current state`);
}

async function applyScalar() {
  const name = $('scalar').value;
  for (let k = 0; k < state.session.docs.length; k++) {
    if (!name || !state.session.docs[k].scalars.some((s) => s.name === name)) { viewer.setScalar(k, null); continue; }
    const { header, data } = await api.scalar(k, name);
    viewer.setScalar(k, data, header);
    if (k === state.active) drawLegend($('legend'), name, header.lo, header.hi, header.clipped);
  }
  if (!name) drawLegend($('legend'), '', 0, 0);
}

function updateLightReadouts() {
  const l = lights[state.active];
  // isophotes and the reflection zebra step an angle
  $('spacing-out').textContent = l.mode === 3 || l.mode === 6
    ? `${(10 * Math.pow(2, l.spacingExp)).toPrecision(3)}°`
    : l.spacing().toPrecision(3);
  $('direction-out').textContent = `${l.directionDeg}°`;
}

function readLightControls() {
  for (const l of lights) {
    l.spacingExp = Number($('spacing').value);
    l.directionDeg = Number($('direction').value);
    l.tiltDeg = Number($('tilt').value);
    l.turnDeg = Number($('turn').value);
    l.bandFraction = Number($('band').value);
    l.lineWidth = Number($('linewidth').value);
    l.sweep = Number($('sweep').value);
    l.mode = Number($('mode').value);
    l.follow = $('follow').value;
    l.radiiText = $('radii').value;
  }
  updateLightReadouts();
  viewer.dirty = true;
}

async function exactLines() {
  const k = state.active;
  const l = lights[k];
  const circ = l.mode === 4 || l.mode === 5;
  const body = circ ? { circular: l.circular(viewer.camera) } : { light: l.array(viewer.camera) };
  if (l.mode === 2 || l.mode === 5) body.band = 0.5 * l.bandFraction * l.spacing();
  const step = shownStep();
  if (step !== undefined) body.step = step;
  state.shown.lines = true;
  status('computing exact lines…');
  const { header, data } = await api.frame(`/api/doc/${k}/lines`, body);
  viewer.setOverlay(k, 'lines', segments(header.lines.concat(header.bands), data), [0.1, 0.9, 1.0, 1]);
  // which state the lines shown belong to (for tests and scripting)
  state.linesShown = { step: step === undefined ? null : step, floats: data.length, first: Array.from(data.slice(0, 3)) };
  showCommand(header.command);
  status(`${header.lines.length} exact lines in ${(header.time_s * 1000).toFixed(0)} ms of server time`);
}

async function detect() {
  const k = state.active;
  status('detecting irregularities…');
  const body = { light: lights[k].array(viewer.camera) };
  const step = shownStep();
  if (step !== undefined) body.step = step;
  state.shown.detect = true;
  const { header, data } = await api.frame(`/api/doc/${k}/detect`, body);
  viewer.setOverlay(k, 'lines', segments(header.lines, data), [0.1, 0.9, 1.0, 1]);
  viewer.setOverlay(k, 'stretches', segments(header.stretches.map((s) => ({ start: s.start, count: s.count, closed: false })), data), [1.0, 0.15, 0.1, 1]);
  state.detected = header.regions;
  const ol = $('regions');
  ol.replaceChildren();
  header.regions.forEach((r, i) => {
    const li = document.createElement('li');
    // a region only the flat-spot measure flagged scores below its threshold
    const what = r.score > r.threshold || !(r.flat_spot > 0) ? `score ${r.score.toPrecision(3)}` : `flat spot ${r.flat_spot.toPrecision(2)}`;
    li.textContent = `${what}, ${r.faces.length} faces`;
    li.dataset.region = String(i);
    li.addEventListener('click', () => takeRegion(i));
    ol.append(li);
  });
  showCommand(header.command);
  // where the measure did not look: "no region" is no verdict there
  const notJudged = header.sites ? Math.round(100 * header.shape_sites / header.sites) : 0;
  const unjudged = notJudged > 0 ? `; ${notJudged} % of the sites not judged (shape finer than the smooth radius ${header.smooth_radius.toPrecision(3)})` : '';
  status(`${header.regions.length} region(s), ${header.stretches.length} irregular stretch(es)${unjudged}`);
}

async function takeRegion(i) {
  const r = state.detected[i];
  // the margin fairing needs (two rings, DESIGN.md §3) is added by the server
  const grown = await api.json(`/api/doc/${state.active}/region`, { op: 'grow', faces: r.faces, rings: 2 });
  setRegion(grown.faces);
  viewer.camera.target = r.center.slice();
  viewer.camera.distance = Math.max(viewer.camera.distance * 0.5, activeDoc().radius * 0.4);
  viewer.dirty = true;
}

function setRegion(faces) { setRegionOf(state.active, faces); }

function setRegionOf(k, faces) {
  state.regions[k] = faces;
  viewer.setRegion(k, faces);
  if (k === state.active) $('regioninfo').textContent = faces.length ? `${faces.length} triangles marked` : '';
}

let pickBusy = false;
async function onPick(e, phase) {
  const tool = $('tool').value;
  if (tool === 'orbit') return false;
  // shift-drag pans, except with the probe (shift-click: a second point)
  if (e.shiftKey && tool !== 'probe') return false;
  if (tool === 'probe') {
    if (phase !== 'down') return true;
    const hit = viewer.pickAt(...local($('gl'), e));
    if (hit) {
      const l = lights[hit.doc];
      const linear = l && !(l.mode === 4 || l.mode === 5);
      await tools.probe(hit.doc, hit.face, hit.point, e.shiftKey, linear ? l.array(viewer.camera) : undefined);
    }
    return true;
  }
  if (tool === 'section') {
    if (phase !== 'down') return true;
    const hit = viewer.pickAt(...local($('gl'), e));
    if (hit) await shape.cut(hit.doc, hit.point);
    return true;
  }
  if (tool === 'endpoints') {
    // a click on a pre-image picks an endpoint, as in the (u, v) panel
    if (phase !== 'down' || !uvPanel || !uvPanel.lines.length) return true;
    const n = nearestLinePoint(...local($('gl'), e));
    if (n.dist < 8) uvPanel.pick(n.line, n.k);
    return true;
  }
  if (pickBusy) return true;
  const [x, y] = local($('gl'), e);
  const hit = viewer.pickAt(x, y);
  if (!hit) return true;
  state.active = hit.doc;
  pickBusy = true;
  try {
    const radius = Number($('sphere-radius').value) * state.session.docs[hit.doc].radius;
    const sphere = await api.json(`/api/doc/${hit.doc}/region`, { op: 'sphere', center: hit.point, radius });
    const current = new Set(tool === 'sphere' && phase === 'down' ? [] : (state.regions[hit.doc] || []));
    for (const f of sphere.faces.length ? sphere.faces : [hit.face]) {
      if (tool === 'erase') current.delete(f); else current.add(f);
    }
    setRegion([...current].sort((a, b) => a - b));
  } catch (err) { status(err.message, true); }
  pickBusy = false;
  return true;
}

async function growShrink(op) {
  const faces = state.regions[state.active] || [];
  if (!faces.length) { status('mark a region first', true); return; }
  const r = await api.json(`/api/doc/${state.active}/region`, { op, faces, rings: 1 });
  setRegion(r.faces);
}

async function run() {
  const k = state.active;
  const [method, sub] = $('method').value.split(':');
  const faces = state.regions[k] || [];
  const body = { method, options: {} };
  if (faces.length) body.faces = faces;
  if (method === 'fair') { body.light = lights[k].array(viewer.camera); body.options.method = sub; }
  if (method === 'smooth') body.options.method = sub;
  const it = Number($('iterations').value);
  if (it > 0) { body.options[method === 'fair' ? 'max_iterations' : 'iterations'] = it; }
  if (method === 'fair' && !faces.length) { status('highlight-line fairing needs a marked region', true); return; }
  await runJob(k, body);
}

async function runJob(k, body) {
  const method = body.method;
  const { job } = await api.json(`/api/doc/${k}/run`, body);
  state.job = job;
  $('cancel').disabled = false;
  $('run').disabled = true;
  status(`${method} running…`);
  for (;;) {
    await new Promise((r) => setTimeout(r, 150));
    const j = await api.json('/api/job');
    $('progress').value = j.progress;
    if (j.state === 'running') { if (j.stage) status(`${method} running: ${j.stage} ${Math.round(100 * j.progress)} %`); continue; }
    if (j.state === 'cancelling') { status(`${method}: ${j.message}`); continue; }
    $('cancel').disabled = true;
    $('run').disabled = false;
    if (j.state === 'done') {
      state.before = false;
      $('before').checked = false;
      await reloadActive();
      showReport(j.report);
      showCommand(j.command);
      status(`${j.label}: done in ${j.report.time_s ? j.report.time_s.toFixed(2) : '?'} s${j.report.converged === false ? ' (did not converge)' : ''}`);
      document.body.dataset.lastJob = 'done';
    } else {
      status(`${j.label}: ${j.state}: ${j.message}`, j.state === 'failed');
      document.body.dataset.lastJob = j.state;
    }
    return;
  }
}

async function historyMove(dir) {
  try {
    await api.json(`/api/doc/${state.active}/${dir}`, {});
    state.before = false;
    $('before').checked = false;
    await reloadActive();
    status(dir === 'undo' ? 'undone' : 'redone');
  } catch (err) { status(err.message, true); }
}

// A click on a history item: undo or redo step by step up to it.
async function jumpTo(i) {
  const d = activeDoc();
  const by = i - d.history.cursor;
  if (!by) return;
  for (let n = 0; n < Math.abs(by); n++) await api.json(`/api/doc/${state.active}/${by < 0 ? 'undo' : 'redo'}`, {});
  state.before = false;
  $('before').checked = false;
  await reloadActive();
  status(`at step ${i}: ${activeDoc().history.steps[i].label}`);
}

// Moves document k to history step `cursor` (a session's position) when
// its history has the same steps up to it; otherwise says so.
async function jumpDoc(k, cursor, steps) {
  const d = state.session.docs[k];
  const labels = (steps || []).map((s) => s.label);
  const same = labels.length === cursor + 1 && labels.every((l, i) => d.history.steps[i] && d.history.steps[i].label === l);
  if (cursor === d.history.cursor) return;
  if (!same || cursor >= d.history.steps.length) {
    status(`${d.name}: the session's step ${cursor} is not in this history; open it with fairline view --session FILE`, true);
    return;
  }
  const active = state.active;
  state.active = k;
  await jumpTo(cursor);
  state.active = active;
}

// Makes document k the one the panels, run, undo and save act on.
function activate(k) {
  if (k === state.active) return;
  state.active = k;
  showSession();
  status(`active: ${activeDoc().name}`);
}

// The view rendered at the size in the View panel, offered as a PNG named
// after the active file and the size.
async function captureImage() {
  const w = Number($('cap-w').value), h = Number($('cap-h').value);
  const blob = await capture(viewer, w, h);
  const name = `${activeDoc().name.replace(/\.[^.]*$/, '')}-${w}x${h}.png`;
  state.lastDownload = { name, bytes: blob.size };
  offer(blob, name);
  status(`image ${name} (${blob.size} bytes)`);
}

async function downloadRegion(what) {
  const faces = state.regions[state.active] || [];
  if (!faces.length) { status('mark a region first', true); return; }
  const r = await api.json(`/api/doc/${state.active}/region-file`, { faces });
  const value = what === 'region' ? r.region : r.fixed;
  state.lastDownload = { name: `${what}.json`, value };
  offerJson(value, `${what}.json`);
}

function downloadLights() {
  const l = lights[state.active];
  const value = l.mode === 4 || l.mode === 5 ? l.circular(viewer.camera) : l.array(viewer.camera);
  state.lastDownload = { name: 'lights.json', value };
  offerJson(value, 'lights.json');
}

// The highlight lines of the current lights as IGES curves for CAD.
async function downloadCurves() {
  const k = state.active;
  const l = lights[k];
  const circ = l.mode === 4 || l.mode === 5;
  const body = circ ? { circular: l.circular(viewer.camera) } : { light: l.array(viewer.camera) };
  const step = shownStep();
  if (step !== undefined) body.step = step;
  status('fitting curves to the lines…');
  const r = await api.json(`/api/doc/${k}/lines-curves`, body);
  state.lastDownload = { name: r.name, curves: r.curves };
  offer(new Blob([r.iges], { type: 'model/iges' }), r.name);
  showCommand(r.command);
  const c = r.curves;
  status(`${c.curves} curves in ${r.name}: ${c.control_points} control points for ${c.points} line points, within ${c.tolerance.toPrecision(2)}${c.polylines ? `; ${c.polylines} short lines as polylines` : ''}`);
}

async function downloadMesh() {
  const fmt = $('dl-format').value;
  const { blob, disposition } = await api.blob(`/api/doc/${state.active}/download?format=${fmt}`);
  const m = /filename="([^"]+)"/.exec(disposition);
  offer(blob, m ? m[1] : `mesh.${fmt}`);
}

async function save() {
  const name = $('save-name').value.trim();
  const url = `/api/doc/${state.active}/save`;
  let r;
  try {
    r = await api.json(url, { name });
  } catch (e) {
    // an existing file is replaced only when the user says so
    if (!/exists in the save folder/.test(String(e.message)) || !window.confirm(`${name} exists in the save folder. Replace it?`)) throw e;
    r = await api.json(url, { name, overwrite: true });
  }
  status(`saved ${r.path} (${r.bytes} bytes)`);
  showCommand(r.command);
}

// ---- B-spline surfaces: patch outlines and labels, the (u, v) panel ----

async function loadOutlines(k, step) {
  const { header, data } = await api.frame(`/api/doc/${k}/outlines${step === undefined ? '' : `?step=${step}`}`);
  viewer.setOverlay(k, 'patches', segmentsOf(header.lines, data), [0.1, 0.15, 0.45, 1]);
  state.labels[k] = header.labels;
}

function segmentsOf(lines, data) { return segments(lines, data); }

// The projection of document k's view: point p (relative to the document's
// centre) → CSS pixel in the canvas, or null when it is behind the camera,
// outside the view or not given.
function projector(k) {
  const vp = viewer.viewport(k);
  const dpr = window.devicePixelRatio || 1;
  const m = viewer.camera.viewProj(vp[2] / vp[3]);
  const cw = viewer.canvas.clientWidth, ch = viewer.canvas.clientHeight;
  return (p) => {
    if (!p) return null;
    const x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    const w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    if (w <= 0) return null;
    const sx = (vp[0] + (x / w * 0.5 + 0.5) * vp[2]) / dpr;
    const sy = ch - (vp[1] + (y / w * 0.5 + 0.5) * vp[3]) / dpr;
    if (sx < 0 || sy < 0 || sx > cw || sy > ch) return null;
    return [sx, sy];
  };
}

function placeLabels() {
  const box = $('labels');
  const spans = [];
  state.labels.forEach((pts, k) => {
    if (!pts) return;
    const screenOf = projector(k);
    pts.forEach((p, i) => {
      const s = screenOf(p);
      if (!s) return;
      const span = document.createElement('span');
      span.textContent = String(i);
      span.style.left = `${s[0]}px`;
      span.style.top = `${s[1]}px`;
      spans.push(span);
    });
  });
  box.replaceChildren(...spans);
}

// ---- the (u, v) pre-images in the 3-D view (linked with the panel) ----

// 3-D point k of pre-image i of the (u, v) panel (same index in both views).
function linePoint(i, k) {
  const l = uvPanel && uvPanel.lines[i];
  if (!l || !state.uvData || k < 0 || k >= l.count) return null;
  const a = 3 * (l.start + k);
  return [state.uvData[a], state.uvData[a + 1], state.uvData[a + 2]];
}

// The visible pre-image point nearest to CSS pixel (x, y) of the 3-D view
// within `reach` CSS pixels: {line, k, dist} (dist in CSS pixels; line −1
// when none). Points on the far side of the part, which project onto it,
// are not candidates: the depth-tested pick pass decides
// (`Viewer.isVisible`), with a tolerance of three pixels at the point's
// depth or 0.5 % of the part's radius, whichever is larger (the pre-images
// lie on the exact surface, the tessellation within its chord error).
function nearestLinePoint(x, y, reach = 8) {
  const best = { line: -1, k: -1, dist: Infinity };
  if (!uvPanel) return best;
  const k0 = state.surfaceDoc;
  const screenOf = projector(k0);
  const near = [];
  uvPanel.lines.forEach((l, i) => {
    for (let k = 0; k < l.count; k++) {
      const s = screenOf(linePoint(i, k));
      if (!s) continue;
      const d = Math.hypot(s[0] - x, s[1] - y);
      if (d < reach) near.push({ line: i, k, dist: d });
    }
  });
  near.sort((a, b) => a.dist - b.dist || a.line - b.line || a.k - b.k);
  const vp = viewer.viewport(k0);
  const eye = viewer.camera.eye();
  const pixel = 2 * Math.tan(0.3) / vp[3];
  const radius = state.session.docs[k0].radius;
  for (const n of near) {
    const p = linePoint(n.line, n.k);
    const depth = Math.hypot(p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]);
    if (viewer.isVisible(k0, p, Math.max(3 * pixel * depth, 0.005 * radius))) return n;
  }
  return best;
}

// Hovering a pre-image in the 3-D view lights it up in both views.
function hover3d(e) {
  if (!uvPanel || !uvPanel.lines.length || e.buttons) return;
  const n = nearestLinePoint(...local($('gl'), e));
  uvPanel.setHover(n.dist < 8 ? n.line : -1);
}

// Small crosses at the picked endpoints in the 3-D view.
function showEndpointMarks() {
  const k = state.surfaceDoc;
  const marks = uvPanel.marks.filter((p) => p);
  if (!marks.length) { viewer.setOverlay(k, 'ends', null); return; }
  const r = 0.015 * state.session.docs[k].radius;
  const segs = new Float32Array(marks.length * 18);
  marks.forEach((p, i) => {
    for (let a = 0; a < 3; a++) {
      const o = 18 * i + 6 * a;
      segs.set(p, o); segs.set(p, o + 3);
      segs[o + a] -= r; segs[o + 3 + a] += r;
    }
  });
  viewer.setOverlay(k, 'ends', segs, [1, 1, 0, 1]);
}

let uvPanel = null;

async function uvLines() {
  const k = state.surfaceDoc;
  const patch = Number($('patch').value) || 0;
  const circular = lights[k].circular(viewer.camera);
  status('computing circular pre-images…');
  const { header, data } = await api.frame(`/api/doc/${k}/surface-lines`, { circular, patch });
  uvPanel.set(header, data);
  for (const name of Object.keys(viewer.docs[k].overlays)) if (name.startsWith('circ')) viewer.setOverlay(k, name, null);
  const lines = header.lines.filter((l) => l.kind === 'line');
  const byLight = new Map();
  for (const l of lines) { if (!byLight.has(l.light)) byLight.set(l.light, []); byLight.get(l.light).push(l); }
  for (const [light, ls] of byLight) viewer.setOverlay(k, `circ${light}`, segments(ls, data), rgba(PALETTE[light % PALETTE.length]));
  state.uvData = data;
  state.uvCircular = circular;
  showCommand(header.command);
  status(`${lines.length} circular highlight line(s) on patch ${patch} in ${(header.time_s * 1000).toFixed(0)} ms of server time`);
}

function showEndpoints(list) {
  $('endpoints').textContent = list.length ? list.map((e) => `R=${Number(e.radius).toPrecision(3)}: (${e.start.map((x) => x.toFixed(3))}) → (${e.end.map((x) => x.toFixed(3))})`).join('; ') : 'click a line twice in the (u, v) panel, or in the 3-D view with the tool "endpoints", to pick the endpoints of a stretch';
  if (uvPanel) showEndpointMarks();
}

async function fairSurface() {
  const k = state.surfaceDoc;
  if (!uvPanel.endpoints.length) { status('pick endpoints in the (u, v) panel first', true); return; }
  state.active = k;
  await runJob(k, { method: 'fair-surface', patch: Number($('patch').value) || 0, circular: state.uvCircular, endpoints: uvPanel.endpoints, options: {} });
  if (document.body.dataset.lastJob === 'done') await uvLines();
}

function guard(f) {
  return async (...a) => {
    try { await f(...a); } catch (err) { status(err.message, true); }
  };
}

function wire() {
  for (const id of ['spacing', 'direction', 'tilt', 'turn', 'band', 'linewidth', 'sweep', 'mode', 'follow', 'radii']) {
    $(id).addEventListener('input', readLightControls);
  }
  $('up').addEventListener('change', () => { viewer.camera.up = $('up').value; viewer.dirty = true; });
  document.querySelectorAll('[data-view]').forEach((b) => b.addEventListener('click', () => { viewer.camera.standard(b.dataset.view); viewer.dirty = true; }));
  $('fit').addEventListener('click', () => { viewer.camera.fit(Math.max(...state.session.docs.map((d) => d.radius))); viewer.dirty = true; });
  $('wireframe').addEventListener('change', () => { viewer.wireframe = $('wireframe').checked; viewer.dirty = true; });
  $('scalar').addEventListener('change', guard(async () => { tools.clearDeviation(); shape.clearDraft(); await applyScalar(); }));
  $('deviation').addEventListener('click', guard(() => { shape.clearDraft(); return tools.showDeviation(); }));
  $('dev-show').addEventListener('change', guard(() => (tools.deviation ? tools.showDeviation() : null)));
  $('dev-clear').addEventListener('click', () => tools.clearDeviation());
  $('sec-clear').addEventListener('click', () => shape.clearSection());
  $('sec-comb').addEventListener('change', () => shape.drawSection());
  $('sec-comb-scale').addEventListener('input', () => shape.drawSection());
  $('draft').addEventListener('click', guard(() => { tools.clearDeviation(); return shape.showDraft(); }));
  $('draft-clear').addEventListener('click', () => shape.clearDraft());
  if (state.session.docs.some((d) => d.kind === 'surface')) {
    $('patch-panel').hidden = false;
    const surfaceDoc = () => (activeDoc().kind === 'surface' ? state.active : state.surfaceDoc);
    $('continuity').addEventListener('click', guard(() => surfaceTools.showContinuity(surfaceDoc())));
    $('cont-clear').addEventListener('click', () => surfaceTools.clearContinuity());
    $('control-net').addEventListener('change', guard(() => surfaceTools.showNet(surfaceDoc(), $('control-net').checked)));
    $('iso-combs').addEventListener('change', guard(() => surfaceTools.showIso(surfaceDoc(), $('iso-combs').checked)));
    $('iso-count').addEventListener('change', guard(() => ($('iso-combs').checked ? surfaceTools.showIso(surfaceDoc(), true) : null)));
    $('iso-comb-scale').addEventListener('input', () => surfaceTools.drawIso());
  }
  $('exact').addEventListener('click', guard(exactLines));
  $('detect').addEventListener('click', guard(detect));
  $('clearlines').addEventListener('click', () => { viewer.setOverlay(state.active, 'lines', null); viewer.setOverlay(state.active, 'stretches', null); state.shown = { lines: false, detect: false }; });
  $('grow').addEventListener('click', guard(() => growShrink('grow')));
  $('shrink').addEventListener('click', guard(() => growShrink('shrink')));
  $('clearregion').addEventListener('click', () => setRegion([]));
  $('run').addEventListener('click', guard(run));
  $('cancel').addEventListener('click', guard(() => api.json('/api/job/cancel', {})));
  $('undo').addEventListener('click', guard(() => historyMove('undo')));
  $('redo').addEventListener('click', guard(() => historyMove('redo')));
  $('before').addEventListener('change', guard(async () => {
    state.before = $('before').checked;
    const step = shownStep();
    await loadGeometry(state.active, step);
    // the overlays shown are computed again on the state shown: the lines
    // and the detection of the state before, not the faired state's
    if (state.shown.detect) await detect();
    else if (state.shown.lines) await exactLines();
    status(state.before ? 'showing the state before the last step' : 'showing the current state');
  }));
  $('compare').addEventListener('change', guard(showCompare));
  $('split').addEventListener('input', () => viewer.setSplit(state.active, Number($('split').value)));
  $('dl-lights').addEventListener('click', downloadLights);
  $('dl-region').addEventListener('click', guard(() => downloadRegion('region')));
  $('dl-fixed').addEventListener('click', guard(() => downloadRegion('fixed')));
  $('dl-mesh').addEventListener('click', guard(downloadMesh));
  $('dl-curves').addEventListener('click', guard(downloadCurves));
  $('save').addEventListener('click', guard(save));
  $('capture').addEventListener('click', guard(captureImage));
  $('save-session').addEventListener('click', guard(() => sessionFile.save()));
  $('open-session').addEventListener('change', guard(async () => {
    const f = $('open-session').files[0];
    if (f) await sessionFile.open(f);
    $('open-session').value = '';
  }));
  const views = window.fairline.views = new SavedViews($('views'), viewer, state.session.docs.map((d) => d.name), (v) => {
    $('up').value = v.up;
    status(`view “${v.name}”`);
  });
  $('save-view').addEventListener('click', () => {
    const name = $('view-name').value.trim() || `view ${views.all().length + 1}`;
    views.save(name);
    status(`saved the view “${name}”`);
  });
  if (state.surfaceDoc >= 0) {
    $('surface-panel').hidden = false;
    uvPanel = window.fairline.uvPanel = new UvPanel($('uv'), (line) => {
      const k = state.surfaceDoc;
      viewer.setOverlay(k, 'hover', line ? segments([line], state.uvData) : null, [1, 1, 0.2, 1]);
    }, showEndpoints);
    uvPanel.point3 = linePoint;
    showEndpoints([]);
    $('gl').addEventListener('pointermove', hover3d);
    $('uvlines').addEventListener('click', guard(uvLines));
    $('clear-ends').addEventListener('click', () => uvPanel.clearEndpoints());
    $('fair-surface').addEventListener('click', guard(fairSurface));
    $('dl-endpoints').addEventListener('click', () => {
      const value = { endpoints: uvPanel.endpoints };
      state.lastDownload = { name: 'endpoints.json', value };
      offerJson(value, 'endpoints.json');
    });
  }
  attachControls($('gl'), viewer, (e, phase) => {
    const tool = $('tool').value;
    if (tool === 'orbit' || (e.shiftKey && tool !== 'probe')) return false;
    onPick(e, phase).catch((err) => status(err.message, true));
    return true;
  });
  window.addEventListener('resize', () => { viewer.dirty = true; });
  const help = window.fairline.help = new Help($('help'), $('tool'));
  $('help-button').addEventListener('click', () => help.toggle());
  installShortcuts(shortcutActions(help));
}

// What each keyboard shortcut does (shortcuts.js names them); most press the
// button or change the control a click would.
function shortcutActions(help) {
  const click = (id) => () => { if (!$(id).disabled) $(id).click(); };
  const toggle = (id) => () => { $(id).checked = !$(id).checked; $(id).dispatchEvent(new Event('change')); };
  return {
    help: () => help.toggle(),
    closeHelp: () => help.hide(),
    run: click('run'),
    undo: click('undo'),
    redo: click('redo'),
    save: click('save'),
    before: toggle('before'),
    compare: toggle('compare'),
    wireframe: toggle('wireframe'),
    image: click('capture'),
    resetView: () => { viewer.camera.standard('iso'); $('fit').click(); },
    view: (name) => document.querySelector(`[data-view=${name}]`).click(),
    exact: click('exact'),
    detect: click('detect'),
    deviation: click('deviation'),
    draft: click('draft'),
    continuity: click('continuity'),
    controlNet: () => { if (!$('patch-panel').hidden) toggle('control-net')(); },
    isoCombs: () => { if (!$('patch-panel').hidden) toggle('iso-combs')(); },
    saveSession: () => { sessionFile.save().catch((err) => status(err.message, true)); },
    tool: (name) => {
      if (![...$('tool').options].some((o) => o.value === name)) return;
      $('tool').value = name;
      $('tool').dispatchEvent(new Event('change'));
      status(`tool: ${$('tool').selectedOptions[0].textContent}`);
    },
  };
}

// Stripes this many CSS pixels apart at the first view (the default
// spacing is chosen on the screen, not in model units).
const STRIPE_PX = 20;

// Sets the spacing slider so that the lines of document `d` lie about
// STRIPE_PX apart at the current view: lines of spacing s lie s/ĝ apart on
// the part (ĝ the median |∇d| the server measured), and a model unit at
// the target spans height / (2·distance·tan(fov/2)) pixels.
function defaultSpacing(d) {
  const g = d.gradient_median;
  const h = $('gl').clientHeight;
  if (!(g > 0) || !(h > 0) || !(d.light.spacing > 0)) return;
  const pxPerUnit = h / (2 * viewer.camera.distance * Math.tan(0.3));
  const px = (d.light.spacing / g) * pxPerUnit;
  const s = $('spacing');
  const exp = Math.log2(STRIPE_PX / px);
  s.value = String(Math.max(Number(s.min), Math.min(Number(s.max), exp)));
  window.fairline.stripePx = px * Math.pow(2, Number(s.value));
}

async function start() {
  mark('modules');
  // every session has document 0: its geometry is asked for at once, beside
  // the session and the shaders
  const early = [api.positions(0), api.normals(0), api.indices(0)];
  early.forEach((r) => r.catch(() => {}));
  const [, session] = await Promise.all([
    viewer.init(),
    api.session().then((r) => { mark('session'); return r; }),
  ]);
  state.session = session;
  const docs = state.session.docs;
  $('docnames').textContent = docs.map((d) => `${d.name} (${d.kind}, ${d.vertices} vertices, ${d.triangles} triangles)`).join('  |  ');
  const names = new Set();
  docs.forEach((d) => d.scalars.forEach((s) => names.add(s.name)));
  for (const n of names) { const o = document.createElement('option'); o.value = n; o.textContent = n; $('scalar').append(o); }
  lights = docs.map((d) => new Lights(d.light, d.center, d.radius));
  tools.init(docs);
  frames = new DocFrames($('docframes'), $('gl'), docs.map((d) => d.name), activate);
  viewer.lightUniforms = (k) => lights[k].uniforms(viewer.camera);
  // the first view is the camera rule's of the first document, as in
  // every `fairline` picture of it
  viewer.camera.setPartView(docs[0].view);
  $('up').value = viewer.camera.up;
  await Promise.all(docs.map((_, k) => loadGeometry(k, undefined, k === 0 ? early : undefined)));
  state.surfaceDoc = docs.findIndex((d) => d.kind === 'surface');
  await Promise.all(docs.map((d, k) => (d.kind === 'surface' ? loadOutlines(k) : null)));
  viewer.camera.fit(Math.max(...docs.map((d) => d.radius)));
  defaultSpacing(docs[0]);
  await viewer.ready();
  mark('shaders');
  showSession();
  readLightControls();
  wire();
  viewer.onFrame = () => {
    placeLabels();
    if (!document.body.dataset.ready) { mark('frame'); document.body.dataset.ready = '1'; }
  };
  if (state.session.restore) await sessionFile.apply(state.session.restore);
  viewer.dirty = true;
  status(state.session.restore ? 'ready: session restored' : 'ready');
  window.fairline.viewer = viewer;
  window.fairline.timeline = timeline;
  // for tests and scripting: CSS pixel (page) of point k of pre-image i
  window.fairline.linePointOnPage = (i, k) => {
    const s = projector(state.surfaceDoc)(linePoint(i, k));
    if (!s) return null;
    const r = viewer.canvas.getBoundingClientRect();
    return [r.left + s[0], r.top + s[1]];
  };
  // 3-D point k of pre-image i (document coordinates), for tests
  window.fairline.linePoint = linePoint;
  window.fairline.lights = lights;
  window.fairline.capture = (w, h) => capture(viewer, w, h);
  window.fairline.timeFrames = (n) => viewer.timeFrames(n, (i) => {
    for (const l of lights) l.sweep = (i % 50) / 50;
  });
}

start().catch((err) => { status(err.message, true); console.error(err); });
