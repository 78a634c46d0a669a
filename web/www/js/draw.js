// Drawing: the storeys on show, the marbles and the ghost on the board, the
// micro:bit's LED matrix and the HUD.

import { $, hz, w } from './core.js';
import { stick, STICK_MAX_MG, STICK_RADIUS_PX, tilt } from './input.js';
import { meanCost } from './cost.js';
import { drop, kindsOf, level, placements, storeyFloorMm } from './level.js';
import { drawRace, racing } from './race.js';

let boardCache = null; // the storeys on show drawn at the canvas's size: { key, canvas }

const COLOURS = {
  floor: '#d9cfbd', wall: '#6b5845', hole: '#0b0b0d',
  goal: '#4fbf6f', start: '#cfc3ad', outside: '#16181d',
};

function fitCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const rect = canvas.getBoundingClientRect();
  const width = Math.max(1, Math.round(rect.width * dpr));
  const height = Math.max(1, Math.round(rect.height * dpr));
  if (canvas.width === width && canvas.height === height) return false;
  canvas.width = width;
  canvas.height = height;
  return true;
}

// The maze's height over its width (one storey's map): the board's box is the
// page's width and this much of it high (CSS, capped by the window), so a
// wide maze on a phone leaves no empty bands.
export function fitBoard() {
  $('board-wrap').style.setProperty('--maze-aspect', String(level.edges[level.nz] / level.edges[level.nx]));
}

// Gap between storey maps side by side, in tile pitches.
const MAP_GAP_PITCHES = 0.5;

// mm → canvas px for `maps` storey maps side by side, centred in the canvas;
// map m starts `stride` px after map m - 1.
export function view(canvas, maps) {
  const widthMm = level.edges[level.nx];
  const heightMm = level.edges[level.nz];
  const gapMm = MAP_GAP_PITCHES * level.pitch;
  const totalMm = maps * widthMm + (maps - 1) * gapMm;
  const scale = Math.min(canvas.width / totalMm, canvas.height / heightMm);
  return {
    scale,
    // Whole pixels: tiles drawn side by side then meet without seams.
    x0: Math.round((canvas.width - totalMm * scale) / 2),
    y0: Math.round((canvas.height - heightMm * scale) / 2),
    stride: Math.round((widthMm + gapMm) * scale),
  };
}

function drawMaze(canvas, shown) {
  const cache = document.createElement('canvas');
  cache.width = canvas.width;
  cache.height = canvas.height;
  const g = cache.getContext('2d');
  g.fillStyle = COLOURS.outside;
  g.fillRect(0, 0, cache.width, cache.height);
  const { scale, x0: left, y0, stride } = view(canvas, shown.length);
  const { nx, nz, edges } = level;
  const px = (mm) => Math.round(mm * scale);
  shown.forEach((storey, map) => {
    const x0 = left + map * stride;
    const kinds = kindsOf(storey);
    for (let k = 0; k < nz; k++) {
      for (let i = 0; i < nx; i++) {
        const kind = kinds[k * nx + i];
        const x = x0 + px(edges[i]);
        const y = y0 + px(edges[k]);
        const wd = x0 + px(edges[i + 1]) - x;
        const ht = y0 + px(edges[k + 1]) - y;
        g.fillStyle = [COLOURS.floor, COLOURS.wall, COLOURS.hole, COLOURS.goal, COLOURS.start][kind]
          ?? COLOURS.outside;
        g.fillRect(x, y, wd, ht);
        if (kind !== 1) {
          // Walls above and to the left cast a shadow on the floor: they read as raised.
          const shade = Math.max(1, Math.round(scale * 0.8));
          g.fillStyle = 'rgba(0,0,0,0.22)';
          if (k > 0 && kinds[(k - 1) * nx + i] === 1) g.fillRect(x, y, wd, shade);
          if (i > 0 && kinds[k * nx + i - 1] === 1) g.fillRect(x, y, shade, ht);
        }
        if (kind === 2) {
          const r = Math.min(wd, ht) / 2;
          const grad = g.createRadialGradient(x + wd / 2, y + ht / 2, r * 0.2, x + wd / 2, y + ht / 2, r * 1.1);
          grad.addColorStop(0, '#000');
          grad.addColorStop(1, '#3a332b');
          g.fillStyle = grad;
          g.fillRect(x, y, wd, ht);
        } else if (kind === 3) {
          g.strokeStyle = '#e8ffe8';
          g.lineWidth = Math.max(1, scale * 0.6);
          g.strokeRect(x + wd * 0.2, y + ht * 0.2, wd * 0.6, ht * 0.6);
        }
      }
    }
    if (level.storeys > 1) {
      // Which storey this is (the LEDs show one at a time; the page says which).
      const font = Math.max(11, Math.round(scale * edges[1] * 0.7));
      g.font = `600 ${font}px system-ui, sans-serif`;
      g.fillStyle = 'rgba(255,255,255,0.85)';
      g.textBaseline = 'top';
      const top = storey === level.storeys - 1 ? ' (top)' : '';
      g.fillText(`storey ${storey + 1} of ${level.storeys}${top}`, x0 + 4, y0 + 3);
    }
  });
  return cache;
}

function drawBoard() {
  const canvas = $('board');
  const resized = fitCanvas(canvas);
  const list = placements();
  const key = list.shown.join(',');
  if (resized || !boardCache || boardCache.key !== key) {
    boardCache = { key, canvas: drawMaze(canvas, list.shown) };
  }
  const g = canvas.getContext('2d');
  g.drawImage(boardCache.canvas, 0, 0);
  const { scale, x0, y0, stride } = view(canvas, list.shown.length);
  // The drop: the floor the marble landed on flashes, as the LEDs' does.
  if (drop.at !== null && drop.storey !== null) {
    const glow = w.drop_glow(w.frames() - drop.at) / w.drop_flash();
    const map = list.shown.indexOf(drop.storey);
    if (glow > 0 && map >= 0) {
      g.fillStyle = `rgba(255,236,190,${(0.55 * glow).toFixed(3)})`;
      g.fillRect(x0 + map * stride, y0, Math.round(level.edges[level.nx] * scale),
        Math.round(level.edges[level.nz] * scale));
    }
  }
  const r = level.radius * scale;
  // The ghost first, under the live marbles: translucent, no shadow.
  for (const m of list.ghosts) {
    const x = x0 + m.map * stride + m.x * scale;
    const z = y0 + m.z * scale;
    const sunk = level.restAbove - (m.y - storeyFloorMm(m.storey));
    const rr = r * (1 - 0.5 * Math.max(0, Math.min(1, sunk / (2 * level.radius))));
    g.globalAlpha = m.alpha;
    g.fillStyle = '#cfe3ff';
    g.beginPath();
    g.arc(x, z, rr, 0, 2 * Math.PI);
    g.fill();
    g.globalAlpha = 1;
  }
  for (const m of list.marbles) {
    const x = x0 + m.map * stride + m.x * scale;
    const z = y0 + m.z * scale;
    // Below its rest height on its storey (sinking into a hole): drawn smaller.
    const sunk = level.restAbove - (m.y - storeyFloorMm(m.storey));
    const sink = Math.max(0, Math.min(1, sunk / (2 * level.radius)));
    const rr = r * (1 - 0.5 * sink);
    g.fillStyle = 'rgba(0,0,0,0.25)';
    g.beginPath();
    g.arc(x + rr * 0.25, z + rr * 0.3, rr, 0, 2 * Math.PI);
    g.fill();
    const grad = g.createRadialGradient(x - rr * 0.35, z - rr * 0.35, rr * 0.1, x, z, rr);
    grad.addColorStop(0, '#ffffff');
    grad.addColorStop(0.35, '#b9c3d0');
    grad.addColorStop(1, '#4b5563');
    g.fillStyle = grad;
    g.beginPath();
    g.arc(x, z, rr, 0, 2 * Math.PI);
    g.fill();
  }
  if (stick.active) {
    const dpr = window.devicePixelRatio || 1;
    const rect = canvas.getBoundingClientRect();
    const cx = (stick.x0 - rect.left) * dpr;
    const cy = (stick.y0 - rect.top) * dpr;
    g.strokeStyle = 'rgba(255,176,40,0.8)';
    g.lineWidth = 2 * dpr;
    g.beginPath();
    g.arc(cx, cy, STICK_RADIUS_PX * dpr, 0, 2 * Math.PI);
    g.stroke();
    const [right, up] = tilt();
    g.fillStyle = 'rgba(255,176,40,0.8)';
    g.beginPath();
    g.arc(cx + (right / STICK_MAX_MG) * STICK_RADIUS_PX * dpr,
      cy - (up / STICK_MAX_MG) * STICK_RADIUS_PX * dpr, 10 * dpr, 0, 2 * Math.PI);
    g.fill();
  }
}

function drawLeds() {
  const canvas = $('leds');
  fitCanvas(canvas);
  const g = canvas.getContext('2d');
  const lw = w.led_width();
  const lh = w.led_height();
  const leds = new Uint8Array(w.memory.buffer, w.led_ptr(), lw * lh);
  g.fillStyle = '#0c0d10';
  g.fillRect(0, 0, canvas.width, canvas.height);
  const pitch = Math.min(canvas.width / lw, canvas.height / lh);
  const r = pitch * 0.28;
  for (let y = 0; y < lh; y++) {
    for (let x = 0; x < lw; x++) {
      const v = leds[y * lw + x] / 15;
      const cx = (x + 0.5) * pitch;
      const cy = (y + 0.5) * pitch;
      if (v > 0) {
        g.fillStyle = `rgba(255,40,20,${0.25 * v})`;
        g.beginPath();
        g.arc(cx, cy, r * 1.9, 0, 2 * Math.PI);
        g.fill();
      }
      g.fillStyle = v > 0 ? `rgb(${Math.round(90 + 165 * v)},${Math.round(20 + 60 * v)},20)` : '#2a1c1a';
      g.beginPath();
      g.arc(cx, cy, r, 0, 2 * Math.PI);
      g.fill();
    }
  }
}

// The panel's level: drawn with every frame, and at once by a new attempt
// (beside the best time it shows), not only at the next animation frame.
export function showLevel() {
  const where = w.level_is_custom() ? ' (editor)' : w.level_is_generated() ? ' (generated)' : ` (${w.level_index() + 1})`;
  $('hud-level').textContent = `${level.name}${where}`;
}

function drawHud() {
  const frames = w.clock_frames();
  showLevel();
  // The level clock: it starts at the first tilt that rolls the marble.
  $('hud-time').textContent = frames || w.phase() !== 0
    ? `${(frames / hz).toFixed(1)} / ${w.time_limit_s()} s`
    : `tilt to start (${w.time_limit_s()} s)`;
  $('hud-stepping').textContent = w.stepping_events() ? 'events' : 'fixed';
  // The reading is the board's (x right, z towards the player): shown as the page's tilt.
  $('hud-tilt').textContent = `→ ${-w.reading_x()} mg, ↑ ${w.reading_z()} mg`;
  // The mean: Chromium's clock ticks in 5 µs or coarser, about a frame's cost.
  const cost = meanCost();
  if (cost !== null) $('hud-cost').textContent = `${(cost * 1000).toFixed(1)} µs`;
}

export function draw() {
  if (racing()) {
    drawRace();
    return;
  }
  if (!level) return;
  drawBoard();
  drawLeds();
  drawHud();
}

// The drawn maze is stale (a new attempt): the next frame draws it again.
export function forgetBoard() {
  boardCache = null;
}

// The maze as last drawn under the marbles (a canvas), or null.
export function mazeCanvas() {
  return boardCache?.canvas ?? null;
}
