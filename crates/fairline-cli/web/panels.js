// Side panels: the report table, the command box, the history list, the
// status line and downloads.
const $ = (id) => document.getElementById(id);
export { $ };

export function status(text, isError = false) {
  const s = $('status');
  s.textContent = text;
  s.classList.toggle('error', isError);
  if (isError) console.warn(text);
}

export function showCommand(cmd) {
  $('command').textContent = cmd || '';
}

function fmt(v) {
  if (typeof v === 'number') return Number.isInteger(v) ? String(v) : v.toPrecision(6);
  if (typeof v === 'boolean') return v ? 'yes' : 'no';
  if (v === null || v === undefined) return '';
  if (Array.isArray(v)) return v.length > 6 ? `[${v.length} items]` : JSON.stringify(v);
  if (typeof v === 'object') return JSON.stringify(v).slice(0, 120);
  return String(v);
}

export function showReport(report) {
  const t = $('report');
  t.replaceChildren();
  if (!report) return;
  const order = ['command', 'converged', 'iterations', 'max_displacement', 'movable_vertices', 'willmore_before', 'willmore_after', 'highlight_deviation_before', 'highlight_deviation_after'];
  const keys = [...order.filter((k) => k in report), ...Object.keys(report).filter((k) => !order.includes(k) && k !== 'history')];
  for (const k of keys) {
    const tr = document.createElement('tr');
    const a = document.createElement('td'); a.textContent = k.replaceAll('_', ' ');
    const b = document.createElement('td'); b.textContent = fmt(report[k]);
    tr.append(a, b);
    t.append(tr);
  }
}

export function showHistory(history, onPick) {
  const ol = $('history');
  ol.replaceChildren();
  history.steps.forEach((s, i) => {
    const li = document.createElement('li');
    li.textContent = s.label;
    li.title = i === history.cursor ? `${s.command}\n(the current state)` : `${s.command}\nclick: go to this state (undo or redo up to it)`;
    if (i === history.cursor) li.classList.add('current');
    li.addEventListener('click', () => onPick(i));
    ol.append(li);
  });
}

// Offers `blob` for download as `name`.
export function offer(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
}

export function offerJson(value, name) {
  offer(new Blob([JSON.stringify(value, null, 2) + '\n'], { type: 'application/json' }), name);
}
