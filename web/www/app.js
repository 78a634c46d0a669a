// Marble Rolling's page: loads the game (marble_web.wasm, built from web/src by
// `cargo web`), feeds it the tilt from the keys, a mouse/finger joystick or the
// phone's orientation, runs it at its own frame rate, and draws the maze and the
// micro:bit's LEDs. All game logic is the wasm module's, i.e. the library's:
// the page only moves numbers and pixels. This file starts it; its parts are
// ES modules in js/, loaded by the browser as they are (no bundler): core (the
// module, loaded by hand: web/src/lib.rs says why there is no wasm-bindgen
// glue), input, loop, attempt, draw, ghost, maze, editor, race and hooks.

import { $, answer, loadModule, setUp, status, w } from './js/core.js';
import { keys, onKey, setupStick, toggleOrientation } from './js/input.js';
import { loop } from './js/loop.js';
import { mazeFromUrl } from './js/maze.js';
import { newAttempt, newMaze, nextLevel, playMaze, restart, setStepping, toggleAutopilot } from './js/attempt.js';
import { downloadHex, setupEditor, toggleEditor } from './js/editor.js';
import { testHooks } from './js/hooks.js';
import { raceCommand, racing, toggleRace } from './js/race.js';

async function main() {
  try {
    await loadModule();
  } catch (e) {
    $('fatal').hidden = false;
    $('fatal').textContent = `cannot load the game: ${e.message}`;
    throw e;
  }
  setUp();
  const select = $('level');
  for (let i = 0; i < w.level_count(); i++) {
    select.add(new Option(`${i + 1}. ${answer(w.builtin_name(i))}`, String(i)));
  }
  select.addEventListener('change', () => {
    if (select.value === 'editor' || select.value === 'maze') return;
    w.select_level(Number(select.value));
    newAttempt();
    status('');
    select.blur();
  });
  $('stepping').addEventListener('change', () => {
    setStepping($('stepping').value === 'events');
    $('stepping').blur();
  });
  $('editor-toggle').addEventListener('click', () => toggleEditor());
  $('download-hex').addEventListener('click', downloadHex);
  // While racing, Restart and Next level are the board's A and B.
  const restartOrA = () => (racing() ? raceCommand(1) : restart());
  const nextOrB = () => (racing() ? raceCommand(2) : nextLevel());
  $('restart').addEventListener('click', restartOrA);
  $('next').addEventListener('click', nextOrB);
  $('race').addEventListener('click', toggleRace);
  $('autopilot').addEventListener('click', toggleAutopilot);
  $('new-maze').addEventListener('click', () => { newMaze(); $('new-maze').blur(); });
  $('maze-storeys').addEventListener('change', () => $('maze-storeys').blur());
  $('orientation').addEventListener('click', toggleOrientation);
  // The keys' commands: R restart, N next level, P autopilot, M a new maze.
  const commands = { KeyR: restartOrA, KeyN: nextOrB, KeyP: toggleAutopilot, KeyM: newMaze };
  window.addEventListener('keydown', (e) => onKey(e, true, commands));
  window.addEventListener('keyup', (e) => onKey(e, false, commands));
  // Keys held while the window loses focus never see their keyup.
  window.addEventListener('blur', () => keys.clear());
  setupStick($('board'));
  setupEditor();
  testHooks();
  // Read before the first level's attempt takes the query off the URL.
  const wanted = mazeFromUrl();
  newAttempt();
  if (wanted?.error) {
    status(wanted.error);
  } else if (wanted) {
    if (wanted.storeys >= 1 && wanted.storeys <= 4) $('maze-storeys').value = String(wanted.storeys);
    playMaze(wanted.seed, wanted);
  }
  document.body.dataset.ready = 'true';
  requestAnimationFrame(loop);
}

main();
