// The game loop: one game frame (the step the animation loop and the browser
// test's fast-forward share), 128 frames a second at any refresh rate, and
// what a finished attempt says (its message, the best time).

import { $, hz, levelName, PHASE_WON, status, TICK_FINISHED, TICK_NEW_ATTEMPT, w } from './core.js';
import { tilt } from './input.js';
import { saveGhost } from './ghost.js';
import { newAttempt } from './attempt.js';
import { draw } from './draw.js';
import { recordCost } from './cost.js';
import { bestKey, followStorey } from './level.js';
import { raceFrame, racing } from './race.js';

// Frames one animation frame may catch up on (at 128 frames/s, 62 ms): after a
// longer stall (a hidden tab, a slow machine) the game slows down rather than
// spiralling into ever longer catch-ups.
const MAX_CATCH_UP = 8;

let running = true; // the rAF loop steps the game (the browser test stops it)

// One game frame: the step the animation loop and the test's fast-forward share.
export function frame() {
  if (racing()) {
    raceFrame();
    return 0;
  }
  const [right, up] = tilt();
  w.set_tilt(right, up);
  const t0 = performance.now();
  const flags = w.tick();
  recordCost(performance.now() - t0);
  followStorey();
  if (flags & TICK_FINISHED) finished();
  if (flags & TICK_NEW_ATTEMPT) newAttempt();
  return flags;
}

let last = null;
let acc = 0;

// Plays the game frames `elapsed` ms of wall time are worth: the accumulator
// keeps the remainder, so any refresh rate gives 128 frames a second.
export function advance(elapsed) {
  acc += elapsed;
  const period = 1000 / hz;
  let n = 0;
  while (acc >= period && n < MAX_CATCH_UP) {
    frame();
    acc -= period;
    n++;
  }
  if (n === MAX_CATCH_UP) acc = Math.min(acc, period);
  return n;
}

export function loop(now) {
  if (last !== null && running) advance(now - last);
  last = now;
  draw();
  requestAnimationFrame(loop);
}

export function finished() {
  const phase = w.finished_phase();
  const clock = w.finished_clock();
  const seconds = clock / hz;
  // Named: the page moves on to the next level while the message stays.
  const name = levelName();
  const time = `${seconds.toFixed(2)} s`;
  if (phase === PHASE_WON) {
    const ghost = saveGhost() ? ' · ghost saved' : '';
    // The best time is a person's: the autopilot's runs do not count.
    if (!w.autopilot()) {
      const key = bestKey();
      const best = Number(localStorage.getItem(key));
      if (!best || seconds < best) {
        localStorage.setItem(key, seconds.toFixed(3));
        // Shown at once: the level stays on show for the win's pause.
        $('hud-best').textContent = `${seconds.toFixed(2)} s`;
        status(`${name}: won in ${time}, a new best!${ghost}`);
      } else {
        status(`${name}: won in ${time} (best ${best.toFixed(2)} s)${ghost}`);
      }
    } else {
      status(`${name}: the autopilot won in ${time}${ghost}`);
    }
  } else if (phase === 2) {
    status(`${name}: fell into a hole after ${time}, again`);
  } else if (clock === 0) {
    // The marble never rolled (nobody tilted, or not enough to roll it): the
    // clock, which starts when it does, never ran, so the wait is what to say.
    const waited = `${(w.finished_frames() / hz).toFixed(0)} s`;
    status(`${name}: time's up, the marble did not roll in ${waited} (the clock starts when it does), again`);
  } else {
    status(`${name}: time's up after ${time}, again`);
  }
}

// Whether the animation loop steps the game (the browser test steps it itself).
export function setRunning(on) {
  running = !!on;
}

// Forgets the time the loop had not played yet (the test's fast-forwards).
export function resetCatchUp() {
  acc = 0;
}
