// The help overlay: every keyboard shortcut (from the shortcut table) and
// every marking tool (from the tool list, with its tooltip).
import { SHORTCUTS } from './shortcuts.js';

function row(table, a, b) {
  const tr = document.createElement('tr');
  const k = document.createElement('td');
  const kbd = document.createElement('kbd');
  kbd.textContent = a;
  k.append(kbd);
  const t = document.createElement('td');
  t.textContent = b;
  tr.append(k, t);
  table.append(tr);
}

export class Help {
  constructor(box, toolSelect) {
    this.box = box;
    const keys = box.querySelector('#help-keys');
    for (const s of SHORTCUTS) row(keys, s.keys, s.label);
    const tools = box.querySelector('#help-tools');
    for (const o of toolSelect.options) row(tools, o.textContent, o.title);
    box.addEventListener('click', (e) => { if (e.target === box) this.hide(); });
    box.querySelector('#help-close').addEventListener('click', () => this.hide());
  }
  get visible() { return !this.box.hidden; }
  show() { this.box.hidden = false; }
  hide() { this.box.hidden = true; }
  toggle() { this.box.hidden = !this.box.hidden; }
}
