// The level in play as the page draws it: its geometry (set at each attempt),
// the draw list (which storeys are on show and where each marble is), the
// followed marble's drop to a lower storey, and the key of its best time.

import { levelName, w } from './core.js';
import { GHOST_ALPHA } from './ghost.js';

export let level = null; // geometry of the level in play, for drawing

// The level in play's geometry, from a new attempt on.
export function setLevel(geometry) {
  level = geometry;
}

// The storey the followed marble (the first in play, as the LEDs follow it)
// was on after the last frame, and the frame it last dropped to a lower one.
export const drop = { storey: null, at: null };

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

// The followed marble's storey after a frame: a drop to a lower one starts the
// floor flash (the LED matrix's, `render::drop_glow`).
export function followStorey() {
  if (!level || level.storeys < 2) return;
  const followed = followedMarble();
  if (followed < 0) return;
  const storey = w.marble_storey(followed);
  if (drop.storey !== null && storey < drop.storey) drop.at = w.frames();
  drop.storey = storey;
}

// The first marble in play (the one the LED view follows), or -1.
function followedMarble() {
  const n = w.marble_count();
  for (let m = 0; m < n; m++) if (!w.marble_out(m)) return m;
  return -1;
}

export function bestKey() {
  return `marble-rolling.best.${w.level_is_custom() ? 'editor:' : ''}${levelName()}`;
}
