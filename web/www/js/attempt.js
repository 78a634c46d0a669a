// The level in play: its geometry at each attempt (for drawing), the level
// picker and the panel's best time and ghost, the draw list (which storeys are
// on show and where each marble is) and the buttons' actions.

import { $, levelName, PHASE_WON, status, w } from './core.js';
import { releaseInput } from './input.js';
import { bestKey, drop, followStorey } from './loop.js';
import { GHOST_ALPHA, ghostNote, showGhost } from './ghost.js';
import { mazeArg, newMaze, updateUrl } from './maze.js';
import { fitBoard, forgetBoard } from './draw.js';

export let level = null; // geometry of the level in play, for drawing

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
  level = {
    nx, nz, edges, name, index,
    storeys: w.level_storeys(),
    kinds: [], // per storey, read when first drawn
    radius: w.marble_radius_mm(),
    pitch: w.pitch_mm(),
    restAbove: 0,
    shown: null, // the storeys on show (top first), kept while no marble is in play
    finishedCount: w.finished_count(),
  };
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
  showGhost();
  $('hud-ghost').textContent = ghostNote();
  updateUrl();
}

// The tile kinds of storey `s` (row by row), read from the module once per attempt.
export function kindsOf(s) {
  if (!level.kinds[s]) {
    const { nx, nz } = level;
    const kinds = new Uint8Array(nx * nz);
    for (let k = 0; k < nz; k++) for (let i = 0; i < nx; i++) kinds[k * nx + i] = w.tile_kind(i, k, s);
    level.kinds[s] = kinds;
  }
  return level.kinds[s];
}

// The height of storey `s`'s floor top, mm (eq. 5: y' = s pitches).
export function storeyFloorMm(s) {
  return s * level.pitch;
}

// The tile (column or row) holding `mm`, or -1 outside the maze.
function tileOf(mm) {
  const { edges } = level;
  const n = edges.length - 1;
  if (!(mm >= edges[0] && mm < edges[n])) return -1;
  let i = 0;
  while (i + 1 < n && edges[i + 1] <= mm) i++;
  return i;
}

// The page's draw list: the storeys on show (top first: those with a marble
// in play, side by side when the marbles are on different ones), and where
// each marble in play is drawn, on its own storey's map, over which tile.
// drawBoard draws from it; the browser test reads it.
export function placements() {
  const marbles = [];
  const n = w.marble_count();
  for (let m = 0; m < n; m++) {
    if (w.marble_out(m)) continue;
    marbles.push({
      marble: m, storey: w.marble_storey(m),
      x: w.marble_mm(m, 0), y: w.marble_mm(m, 1), z: w.marble_mm(m, 2),
    });
  }
  if (marbles.length) {
    level.shown = [...new Set(marbles.map((m) => m.storey))].sort((a, b) => b - a);
  } else if (!level.shown) {
    level.shown = [level.storeys - 1];
  }
  for (const m of marbles) {
    m.map = level.shown.indexOf(m.storey);
    m.i = tileOf(m.x);
    m.k = tileOf(m.z);
    m.kind = m.i < 0 || m.k < 0 ? 5 : kindsOf(m.storey)[m.k * level.nx + m.i];
  }
  // The ghost's marbles, on the maps on show (on another storey: not drawn).
  const ghosts = [];
  const g = w.ghost_marble_count();
  for (let m = 0; m < g; m++) {
    if (w.ghost_marble_out(m)) continue;
    const storey = w.ghost_marble_storey(m);
    const map = level.shown.indexOf(storey);
    if (map < 0) continue;
    ghosts.push({
      marble: m, storey, map, alpha: GHOST_ALPHA,
      x: w.ghost_marble_mm(m, 0), y: w.ghost_marble_mm(m, 1), z: w.ghost_marble_mm(m, 2),
    });
  }
  return { storeys: level.storeys, shown: level.shown, marbles, ghosts };
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
