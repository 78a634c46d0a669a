// The browser test's window onto the page: window.marbleState and
// window.marbleTest.

import { $, answer, decoder, hex, levelName, PHASES, status, TICK_FINISHED, TICK_NEW_ATTEMPT, w } from './core.js';
import { keys, orientation, stick, tilt } from './input.js';
import { advance, finished, frame, resetCatchUp, setRunning } from './loop.js';
import { ghostKey, storedGhost } from './ghost.js';
import { mazeArg } from './maze.js';
import { newAttempt, playMaze, restart, setStepping } from './attempt.js';
import { kindsOf, level, placements } from './level.js';
import { draw, mazeCanvas, view } from './draw.js';
import { toggleEditor } from './editor.js';
import { raceState, startRace, stopRace } from './race.js';

// Read-only views and a fast-forward for the browser test (web/test); the
// fast-forward runs the same `frame()` as the animation loop.
export function testHooks() {
  const finishedRecord = () => ({
    count: w.finished_count(),
    level: w.finished_level(),
    custom: !!w.finished_custom(),
    phase: PHASES[w.finished_phase()],
    frames: w.finished_frames(),
    clock: w.finished_clock(),
    hash: hex(w.finished_hash()),
  });
  window.marbleState = () => ({
    level: w.level_index(),
    name: levelName(),
    custom: !!w.level_is_custom(),
    generated: !!w.level_is_generated(),
    maze: w.level_is_generated()
      ? { seed: mazeArg(0), size: mazeArg(1), storeys: mazeArg(2), difficulty: mazeArg(3) }
      : null,
    ghost: w.ghost_active()
      ? {
        frames: w.ghost_frames(), clock: w.ghost_clock_frames(), phase: PHASES[w.ghost_phase()],
        hash: hex(w.ghost_state_hash()),
        record: {
          frames: w.ghost_record(0), clock: w.ghost_record(1), idle: w.ghost_record(2), hash: hex(w.ghost_record_hash()),
        },
      }
      : null,
    phase: PHASES[w.phase()],
    frames: w.frames(),
    clock: w.clock_frames(),
    stepping: w.stepping_events() ? 'events' : 'fixed',
    hash: hex(w.state_hash()),
    autopilot: !!w.autopilot(),
    marbles: Array.from({ length: w.marble_count() }, (_, m) => ({
      x: w.marble_mm(m, 0), y: w.marble_mm(m, 1), z: w.marble_mm(m, 2), out: !!w.marble_out(m),
    })),
    finished: finishedRecord(),
    // What the next frame would take as the tilt, and what the game took last.
    input: {
      tilt: tilt(), reading: [w.reading_x(), w.reading_z()], orientation: { ...orientation },
      stick: stick.active, keys: [...keys],
    },
  });
  // A race through the relay, the autopilot playing after `looks` frames: started, read, stopped.
  window.marbleRace = { start: (channel, looks = 0) => startRace(channel, looks), state: raceState, stop: stopRace };
  window.marbleTest = {
    levels: () => Array.from({ length: w.level_count() }, (_, i) => answer(w.builtin_name(i))),
    setRunning,
    select(index) {
      const ok = !!w.select_level(index);
      newAttempt();
      status('');
      return ok;
    },
    setAutopilot(on) {
      w.set_autopilot(on ? 1 : 0);
      $('autopilot').setAttribute('aria-pressed', String(!!w.autopilot()));
    },
    // `n` frames, stopping after one that finished an attempt if `untilFinished`.
    steps(n, untilFinished = false) {
      for (let i = 0; i < n; i++) {
        if (frame() & TICK_FINISHED && untilFinished) return i + 1;
      }
      return n;
    },
    finished: finishedRecord,
    stepping(name) {
      setStepping(name === 'events');
      return w.stepping_events() ? 'events' : 'fixed';
    },
    placements,
    status: () => $('status').textContent,
    // The level text of a generated maze (as `cargo sim -- --generate SEED
    // --print-level` prints it), or the generator's error.
    mazeText(seed, { size, storeys, difficulty } = {}) {
      const n = w.generate_level(seed >>> 0, size ?? w.default_maze_size(),
        storeys ?? w.default_maze_storeys(), difficulty ?? w.default_maze_difficulty());
      return n >= 0
        ? { text: decoder.decode(new Uint8Array(w.memory.buffer, w.text_ptr(), n)) }
        : { error: answer(-n) };
    },
    playMaze,
    // The text of the editor's level or generated maze in play.
    sourceText: () => decoder.decode(new Uint8Array(w.memory.buffer, w.source_text_ptr(), w.source_text_len())),
    ghostKey,
    storedGhost,
    restartLevel: restart,
    // How far the board's pixel at the first ghost's and the first live
    // marble's centre is from the maze drawn under them (summed over RGB).
    contrast() {
      const canvas = $('board');
      const list = placements();
      const { scale, x0, y0, stride } = view(canvas, list.shown.length);
      const board = canvas.getContext('2d');
      const maze = mazeCanvas().getContext('2d');
      const at = (m) => {
        if (!m) return null;
        const x = Math.round(x0 + m.map * stride + m.x * scale);
        const y = Math.round(y0 + m.z * scale);
        const a = board.getImageData(x, y, 1, 1).data;
        const b = maze.getImageData(x, y, 1, 1).data;
        return Math.abs(a[0] - b[0]) + Math.abs(a[1] - b[1]) + Math.abs(a[2] - b[2]);
      };
      return { ghost: at(list.ghosts[0]), live: at(list.marbles[0]) };
    },
    // The colour drawn at the centre of the first tile of `kind` (as
    // tile_kind numbers them) on the first storey map on show, or null.
    tilePixel(kind) {
      const canvas = $('board');
      const list = placements();
      const { scale, x0, y0 } = view(canvas, list.shown.length);
      const kinds = kindsOf(list.shown[0]);
      const at = kinds.indexOf(kind);
      if (at < 0) return null;
      const [i, k] = [at % level.nx, Math.floor(at / level.nx)];
      const centre = (n) => (level.edges[n] + level.edges[n + 1]) / 2;
      const x = Math.round(x0 + centre(i) * scale);
      const y = Math.round(y0 + centre(k) * scale);
      const [r, g, b] = canvas.getContext('2d').getImageData(x, y, 1, 1).data;
      return { r, g, b };
    },
    editor: toggleEditor,
    // Game frames played by `seconds` of animation frames at `refreshHz`
    // (the loop's own accumulator, fed the timestamps such a screen gives).
    playAt(refreshHz, seconds) {
      resetCatchUp();
      let played = 0;
      for (let i = 0; i < Math.round(refreshHz * seconds); i++) played += advance(1000 / refreshHz);
      return played;
    },
    // Game frames played by one animation frame that comes `ms` late.
    stall(ms) {
      resetCatchUp();
      return advance(ms);
    },
    // The cost of `n` frames in which the game plays (a finished attempt's
    // display frames, which do no physics, are played but not counted), each
    // timed alone with performance.now(), in µs. Chromium rounds that clock
    // to 5 µs in a cross-origin isolated page (100 µs otherwise), so
    // `mean_us` (total / n) and `block_median_us` are the finer figures.
    measure(n) {
      const t = new Float64Array(n);
      let total = 0;
      let counted = 0;
      for (let i = 0; counted < n && i < 16 * n; i++) {
        const playing = w.phase() === 0;
        const [right, up] = tilt();
        w.set_tilt(right, up);
        const t0 = performance.now();
        const flags = w.tick();
        const dt = performance.now() - t0;
        if (flags & TICK_NEW_ATTEMPT) newAttempt();
        if (playing) {
          t[counted++] = dt;
          total += dt;
        }
      }
      const times = t.subarray(0, counted).sort();
      // Then blocks of BLOCK frames timed together, the clock's grain spread
      // over BLOCK (blocks in which an attempt ends are left out): the median
      // block / BLOCK is the typical frame.
      const BLOCK = 64;
      const blocks = [];
      for (let b = 0; blocks.length < n / BLOCK && b < n; b++) {
        const before = w.finished_count();
        const playing = w.phase() === 0;
        const t0 = performance.now();
        for (let i = 0; i < BLOCK; i++) {
          const [right, up] = tilt();
          w.set_tilt(right, up);
          if (w.tick() & TICK_NEW_ATTEMPT) newAttempt();
        }
        const dt = performance.now() - t0;
        if (playing && w.finished_count() === before) blocks.push(dt / BLOCK);
      }
      blocks.sort((a, b) => a - b);
      return {
        block: BLOCK,
        block_median_us: blocks[blocks.length >> 1] * 1000,
        frames: counted,
        median_us: times[counted >> 1] * 1000,
        p99_us: times[Math.floor(counted * 0.99)] * 1000,
        max_us: times[counted - 1] * 1000,
        mean_us: (total / counted) * 1000,
        isolated: window.crossOriginIsolated,
      };
    },
    draw,
  };
}
