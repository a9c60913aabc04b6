// API client: every call carries the access token in the X-Fairline-Token
// header (the token comes from the page URL). Geometry arrives as binary.
const token = new URLSearchParams(location.search).get('token') || '';

async function call(path, options = {}) {
  const headers = Object.assign({ 'X-Fairline-Token': token }, options.headers || {});
  const init = { method: options.method || 'GET', headers };
  if (options.body !== undefined) {
    init.method = 'POST';
    init.body = JSON.stringify(options.body);
    headers['Content-Type'] = 'application/json';
  }
  const r = await fetch(path, init);
  if (!r.ok) {
    let msg = r.statusText;
    try { msg = (await r.json()).error || msg; } catch (_) { /* not JSON */ }
    throw new Error(`${path}: ${msg}`);
  }
  return r;
}

export async function json(path, body) {
  return (await call(path, { body })).json();
}

export async function buffer(path, body) {
  return (await call(path, { body })).arrayBuffer();
}

export async function blob(path) {
  const r = await call(path);
  return { blob: await r.blob(), disposition: r.headers.get('Content-Disposition') || '' };
}

// A binary frame: u32 header length, JSON header, padding to 4, f32 data.
export function parseFrame(buf) {
  const len = new DataView(buf).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, len)));
  const start = Math.ceil((4 + len) / 4) * 4;
  return { header, data: new Float32Array(buf, start) };
}

export async function frame(path, body) {
  return parseFrame(await buffer(path, body));
}

export const session = () => json('/api/session');
export const positions = (k, step) => buffer(`/api/doc/${k}/positions${step === undefined ? '' : `?step=${step}`}`).then((b) => new Float32Array(b));
export const normals = (k, step) => buffer(`/api/doc/${k}/normals${step === undefined ? '' : `?step=${step}`}`).then((b) => new Float32Array(b));
export const indices = (k) => buffer(`/api/doc/${k}/indices`).then((b) => new Uint32Array(b));
export const patches = (k) => buffer(`/api/doc/${k}/patches`).then((b) => new Uint32Array(b));
export const scalar = (k, name) => buffer(`/api/doc/${k}/scalar/${encodeURIComponent(name)}`).then(parseFrame);
