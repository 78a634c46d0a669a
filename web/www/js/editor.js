// The level editor: its text checked by the game's parser as it is typed,
// played, and written into the micro:bit's universal hex (Download for
// micro:bit).

import { $, answer, putText, status, w } from './core.js';
import { newAttempt } from './attempt.js';
import { level } from './level.js';

const TEMPLATE = `name: my-corner
effects: rolling, friction
time_limit_s: 30
---
#########
#S......#
#######.#
#G......#
#########
`;

function showCheck(len) {
  const out = $('source-error');
  if (len === 0) {
    out.textContent = 'ok';
    out.className = 'good';
    return true;
  }
  // The parser's own `line:column: message`.
  out.textContent = answer(len);
  out.className = 'bad';
  return false;
}

export function setupEditor() {
  const source = $('source');
  source.value = localStorage.getItem('marble-rolling.editor') ?? TEMPLATE;
  const check = () => showCheck(w.check_level(putText(source.value)));
  source.addEventListener('input', () => {
    localStorage.setItem('marble-rolling.editor', source.value);
    check();
  });
  check();
  $('play-source').addEventListener('click', () => {
    if (showCheck(w.play_level(putText(source.value)))) {
      newAttempt();
      status(`playing ${level.name} from the editor`);
    }
  });
  // Clicking the message puts the cursor on the line and column it names.
  $('source-error').addEventListener('click', () => {
    const m = /^(\d+):(\d+):/.exec($('source-error').textContent);
    if (!m) return;
    const lines = source.value.split('\n');
    const line = Math.min(Number(m[1]), lines.length) - 1;
    let at = 0;
    for (let i = 0; i < line; i++) at += lines[i].length + 1;
    at += Math.min(Number(m[2]) - 1, lines[line].length);
    source.focus();
    source.setSelectionRange(at, at + 1);
  });
}

// The universal hex `cargo xtask hex` built, as the server hands it out
// (fetched at the first download): the module writes the level into it.
let servedHex = null;

// Says how the download went under its button: `kind` is 'good', 'warn'
// (saved, but a board cannot show the level) or 'bad' (not saved: why).
function downloadSays(text, kind) {
  const out = $('download-status');
  out.textContent = text;
  out.className = kind;
}

// Writes the editor's level into the micro:bit's universal hex (the module
// checks it for each board and writes the levels region) and saves the file.
export async function downloadHex() {
  if (!servedHex) {
    let response;
    try {
      response = await fetch('marble-rolling.hex');
    } catch (e) {
      downloadSays(`cannot download: the micro:bit .hex did not load (${e.message})`, 'bad');
      return;
    }
    if (!response.ok) {
      downloadSays(`cannot download: this page is served without the micro:bit .hex (HTTP ${response.status}); `
        + 'run `cargo xtask hex`, then reload the page', 'bad');
      return;
    }
    servedHex = new Uint8Array(await response.arrayBuffer());
  }
  if (servedHex.length > w.hex_capacity()) {
    downloadSays(`cannot download: the served .hex is ${servedHex.length} B, the page takes up to ${w.hex_capacity()} B`, 'bad');
    return;
  }
  new Uint8Array(w.memory.buffer, w.hex_ptr(), servedHex.length).set(servedHex);
  const n = w.download_hex(putText($('source').value), servedHex.length);
  if (n <= 0) {
    downloadSays(`cannot download: ${answer(-n)}`, 'bad');
    return;
  }
  const bytes = new Uint8Array(w.memory.buffer, w.hex_out_ptr(), n).slice();
  const noteLen = w.download_note();
  const note = noteLen ? `; ${answer(noteLen)}` : '';
  const name = answer(w.download_name()).replace(/[^A-Za-z0-9._-]+/g, '-').slice(0, 60) || 'level';
  const file = `marble-rolling-${name}.hex`;
  const url = URL.createObjectURL(new Blob([bytes], { type: 'application/octet-stream' }));
  const link = document.createElement('a');
  link.href = url;
  link.download = file;
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60000);
  downloadSays(`${file} (${Math.round(n / 1024)} KiB): copy it onto the MICROBIT drive, `
    + `the board plays this level first${note}`, note ? 'warn' : 'good');
}

// Shows the editor (or hides it again): behind a button, so a phone's first
// screen is the maze and its panel.
export function toggleEditor(open) {
  const editor = $('editor');
  const show = open ?? editor.hidden;
  editor.hidden = !show;
  $('editor-toggle').setAttribute('aria-expanded', String(show));
  if (show) editor.scrollIntoView({ block: 'nearest' });
}
