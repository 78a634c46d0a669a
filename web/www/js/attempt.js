// Attempts: a new one sets the level's geometry (for drawing), the level
// picker and the panel's best time and ghost; the buttons' actions, and
// playing a generated maze.

import { $, answer, levelName, PHASE_WON, status, w } from './core.js';
import { releaseInput } from './input.js';
import { ghostNote, showGhost } from './ghost.js';
import { mazeArg, updateUrl } from './maze.js';
import { fitBoard, forgetBoard, showLevel } from './draw.js';
import { bestKey, drop, followStorey, level, setLevel, storeyFloorMm } from './level.js';

// A new level or a restart: its geometry, the picker, the best time; held
// input is let go at a new level.
export function newAttempt() {
  const nx = w.level_nx();
  const nz = w.level_nz();
  const edges = new Float64Array(Math.max(nx, nz) + 1);
  for (let i = 0; i < edges.length; i++) edges[i] = w.tile_edge_mm(i);
  const name = levelName();
  const index = w.level_is_custom() ? -1 : w.level_index();
  // Also after a win on the same level (a generated maze plays again).
  const won = level && w.finished_count() !== level.finishedCount && w.finished_phase() === PHASE_WON;
  if (level && (level.index !== index || level.name !== name || won)) releaseInput();
  setLevel({
    nx, nz, edges, name, index,
    storeys: w.level_storeys(),
    kinds: [], // per storey, read when first drawn
    radius: w.marble_radius_mm(),
    pitch: w.pitch_mm(),
    restAbove: 0,
    shown: null, // the storeys on show (top first), kept while no marble is in play
    finishedCount: w.finished_count(),
  });
  // Where a marble rests above its storey's floor: it starts there.
  level.restAbove = w.marble_mm(0, 1) - storeyFloorMm(w.marble_storey(0));
  drop.storey = null;
  drop.at = null;
  followStorey();
  forgetBoard();
  fitBoard();
  const select = $('level');
  const custom = w.level_is_custom();
  const generated = w.level_is_generated();
  select.querySelector('option[value="editor"]')?.remove();
  select.querySelector('option[value="maze"]')?.remove();
  if (custom) select.add(new Option(`${level.name} (editor)`, 'editor'));
  if (generated) select.add(new Option(`maze ${mazeArg(0)} (generated)`, 'maze'));
  select.value = custom ? 'editor' : generated ? 'maze' : String(w.level_index());
  $('stepping').value = w.stepping_events() ? 'events' : 'fixed';
  const best = Number(localStorage.getItem(bestKey()));
  $('hud-best').textContent = best ? `${best.toFixed(2)} s` : '–';
  showLevel();
  showGhost();
  $('hud-ghost').textContent = ghostNote();
  updateUrl();
}

export function restart() {
  w.restart();
  newAttempt();
  status('');
}

// The next built-in level; on a generated maze (which plays alone, and again
// after a win) a new maze like it.
export function nextLevel() {
  if (w.level_is_generated()) {
    newMaze();
    return;
  }
  w.next_level();
  newAttempt();
  status('');
}

export function setStepping(events) {
  w.set_stepping(events ? 1 : 0);
  newAttempt();
  status(`${events ? 'event' : 'fixed'} stepping: ${level.name} from its start`);
}

export function toggleAutopilot() {
  w.set_autopilot(w.autopilot() ? 0 : 1);
  $('autopilot').setAttribute('aria-pressed', String(!!w.autopilot()));
}

// The maze of `seed` (the arguments of `cargo sim -- --generate`; those not
// given take its defaults): true if it plays, else the generator's message.
export function playMaze(seed, { size, storeys, difficulty } = {}) {
  const err = w.play_generated(seed >>> 0, size ?? w.default_maze_size(),
    storeys ?? w.default_maze_storeys(), difficulty ?? w.default_maze_difficulty());
  if (err) {
    status(`maze ${seed}: ${answer(err)}`);
    return false;
  }
  newAttempt();
  status(`maze ${seed}: ${level.name}, generated (the URL plays it again)`);
  return true;
}

// A new seed (the browser's random numbers), with the storeys picked beside
// the button and the size and difficulty of the maze in play, if one is.
export function newMaze() {
  const seed = crypto.getRandomValues(new Uint32Array(1))[0];
  const generated = w.level_is_generated();
  playMaze(seed, {
    storeys: Number($('maze-storeys').value),
    size: generated ? mazeArg(1) : undefined,
    difficulty: generated ? mazeArg(3) : undefined,
  });
}
