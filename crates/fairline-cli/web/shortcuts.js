// Keyboard shortcuts: one table (keys, what they do, the action's name) that
// both the key handler and the help overlay read. Keys typed into a text
// field, a number field or a list stay there.

export const SHORTCUTS = [
  { keys: '?', label: 'show or hide this help', action: 'help' },
  { keys: 'Escape', label: 'close this help', action: 'closeHelp' },
  { keys: 'Ctrl+Enter', label: 'run the chosen repair method (also in a field)', action: 'run', anywhere: true },
  { keys: 'Ctrl+Z', label: 'undo the last step', action: 'undo' },
  { keys: 'Ctrl+Shift+Z', label: 'redo', action: 'redo' },
  { keys: 'Ctrl+Y', label: 'redo', action: 'redo' },
  { keys: 'Ctrl+S', label: 'save the current state under the name given (also in a field)', action: 'save', anywhere: true },
  { keys: 'B', label: 'toggle before / after the last step', action: 'before' },
  { keys: 'Shift+B', label: 'before / after split view with a divider on / off', action: 'compare' },
  { keys: 'F', label: 'reset the view: fit every document, seen from iso', action: 'resetView' },
  { keys: '1', label: 'view from the front', action: 'view:front' },
  { keys: '2', label: 'view from the back', action: 'view:back' },
  { keys: '3', label: 'view from the left', action: 'view:left' },
  { keys: '4', label: 'view from the right', action: 'view:right' },
  { keys: '5', label: 'view from the top', action: 'view:top' },
  { keys: '6', label: 'view from the bottom', action: 'view:bottom' },
  { keys: '0', label: 'iso view', action: 'view:iso' },
  { keys: 'W', label: 'wireframe on / off', action: 'wireframe' },
  { keys: 'I', label: 'download an image of the view at the size given (View panel)', action: 'image' },
  { keys: 'L', label: 'exact highlight lines', action: 'exact' },
  { keys: 'D', label: 'detect irregularities', action: 'detect' },
  { keys: 'V', label: 'deviation map (Measure panel)', action: 'deviation' },
  { keys: 'O', label: 'tool: orbit only', action: 'tool:orbit' },
  { keys: 'P', label: 'tool: paint faces', action: 'tool:paint' },
  { keys: 'E', label: 'tool: erase faces', action: 'tool:erase' },
  { keys: 'S', label: 'tool: sphere', action: 'tool:sphere' },
  { keys: 'N', label: 'tool: endpoints', action: 'tool:endpoints' },
  { keys: 'M', label: 'tool: probe (measure)', action: 'tool:probe' },
  { keys: 'X', label: 'tool: section', action: 'tool:section' },
  { keys: 'A', label: 'draft-angle map (Draft panel)', action: 'draft' },
  { keys: 'C', label: 'continuity of the patch edges (surfaces)', action: 'continuity' },
  { keys: 'K', label: 'control net on / off (surfaces)', action: 'controlNet' },
  { keys: 'U', label: 'iso-curve curvature combs on / off (surfaces)', action: 'isoCombs' },
  { keys: 'Ctrl+Shift+S', label: 'save the session (file, lights, view, marks, history) as JSON', action: 'saveSession', anywhere: true },
];

// Whether key event `e` is the combination `keys` ("Ctrl+Shift+Z", "?").
// Ctrl also matches the Mac's Command key; Shift is part of a letter's
// combination, not of a symbol's ("?" is typed with Shift).
export function matches(keys, e) {
  const parts = keys.split('+');
  const key = parts.pop();
  const ctrl = parts.includes('Ctrl'), shift = parts.includes('Shift');
  if ((e.ctrlKey || e.metaKey) !== ctrl || e.altKey) return false;
  const letter = /^[A-Z]$/.test(key);
  if (letter) return e.key.toUpperCase() === key && e.shiftKey === shift;
  return e.key === key;
}

// Whether the keys go to a field being typed into.
function typing(target) {
  if (!target || !target.closest) return false;
  const field = target.closest('input, textarea, select, [contenteditable]');
  if (!field) return false;
  return !(field.tagName === 'INPUT' && ['checkbox', 'radio', 'range', 'button'].includes(field.type));
}

// Calls `actions[name](arg)` for the first shortcut matching a key press.
export function installShortcuts(actions) {
  window.addEventListener('keydown', (e) => {
    if (e.repeat) return;
    const s = SHORTCUTS.find((x) => matches(x.keys, e));
    if (!s || (typing(e.target) && !s.anywhere)) return;
    const [name, arg] = s.action.split(':');
    if (!actions[name]) return;
    e.preventDefault();
    actions[name](arg);
  });
}
