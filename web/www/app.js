// Marble Rolling's page: loads the game (marble_web.wasm, built from web/src by
// `cargo web`), feeds it the tilt from the keys, a mouse/finger joystick or the
// phone's orientation, runs it at its own frame rate, and draws the maze and the
// micro:bit's LEDs. All game logic is the wasm module's, i.e. the library's:
// this file only moves numbers and pixels. It loads the module by hand (see
// web/src/lib.rs for why there is no wasm-bindgen glue).

// Held keys tilt the board this far (milli-g, per axis): enough to roll
// briskly, well short of the 500 mg the terminal's keys reach.
const KEY_TILT_MG = 300;
// The joystick's full deflection (px from where the drag began) and the tilt it gives.
const STICK_RADIUS_PX = 80;
const STICK_MAX_MG = 500;
// The phone's tilt is clamped to this (a phone held at 40° would give 640 mg).
const ORIENTATION_MAX_MG = 600;
// Frames one animation frame may catch up on (at 128 frames/s, 62 ms): after a
// longer stall (a hidden tab, a slow machine) the game slows down rather than
// spiralling into ever longer catch-ups.
const MAX_CATCH_UP = 8;
// Frames whose mean cost the HUD shows.
const COST_WINDOW = 256;
// The ghost marble's opacity: dimmer than the live one, which is drawn opaque.
const GHOST_ALPHA = 0.4;

const PHASES = ['playing', 'won', 'fell', 'timeout'];
const PHASE_WON = 1;
const TICK_FINISHED = 1;
const TICK_NEW_ATTEMPT = 2;

const $ = (id) => document.getElementById(id);
const encoder = new TextEncoder();
const decoder = new TextDecoder();

let w; // the module's exports
let hz; // game frames per second
let running = true; // the rAF loop steps the game (the browser test stops it)
const keys = new Set(); // held tilt keys: 'left', 'right', 'up', 'down'
const stick = { active: false, x0: 0, y0: 0, x: 0, y: 0 };
const orientation = { on: false, neutral: null, right: 0, up: 0 };
const costs = new Float64Array(COST_WINDOW);
let costCount = 0;
let level = null; // geometry of the level in play, for drawing
let boardCache = null; // the storeys on show drawn at the canvas's size: { key, canvas }
// The storey the followed marble (the first in play, as the LEDs follow it)
// was on after the last frame, and the frame it last dropped to a lower one.
const drop = { storey: null, at: null };
// The stored ghost the module plays (its storage key and base64), so that a
// restart does not load and check it again.
let ghostShown = null;

async function load() {
  const response = fetch('marble_web.wasm');
  let instance;
  try {
    ({ instance } = await WebAssembly.instantiateStreaming(response, {}));
  } catch (e) {
    // A server without application/wasm: compile from the bytes instead.
    const bytes = await (await fetch('marble_web.wasm')).arrayBuffer();
    ({ instance } = await WebAssembly.instantiate(bytes, {}));
  }
  return instance.exports;
}

// An answer the module wrote to its output buffer (`len` bytes of UTF-8).
function answer(len) {
  return decoder.decode(new Uint8Array(w.memory.buffer, w.out_ptr(), len));
}

// Puts `text` in the module's text buffer; returns the byte count to pass on.
// A text longer than the buffer (no level is) hands over the whole lines that
// fit, marked as cut: the module then shows the first error in them (a grid
// over the size limit says so on its first rows), else the length.
function putText(text) {
  const cap = w.text_capacity();
  const dst = new Uint8Array(w.memory.buffer, w.text_ptr(), cap);
  const { read, written } = encoder.encodeInto(text, dst);
  if (read === text.length) return written;
  const fits = text.slice(0, read);
  const lines = encoder.encodeInto(fits.slice(0, fits.lastIndexOf('\n') + 1), dst);
  return lines.written | w.text_cut();
}

function hex(u64) {
  return BigInt.asUintN(64, BigInt(u64)).toString(16).padStart(16, '0');
}

function levelName() {
  return answer(w.level_name());
}

// --- input -------------------------------------------------------------------

const KEY_DIRS = {
  ArrowLeft: 'left', KeyA: 'left',
  ArrowRight: 'right', KeyD: 'right',
  ArrowUp: 'up', KeyW: 'up',
  ArrowDown: 'down', KeyS: 'down',
};

function typing(event) {
  const t = event.target;
  return t && (t.tagName === 'TEXTAREA' || t.tagName === 'INPUT' || t.tagName === 'SELECT');
}

function onKey(event, down) {
  if (typing(event)) return;
  const dir = KEY_DIRS[event.code];
  if (dir) {
    // A key released by a level change (releaseInput) stays released until
    // it is pressed again: its auto-repeats do not count as a new press.
    if (down && !event.repeat) keys.add(dir);
    else if (!down) keys.delete(dir);
    event.preventDefault();
    return;
  }
  if (!down || event.repeat) return;
  switch (event.code) {
    case 'Space': keys.clear(); stick.active = false; orientation.neutral = null; break;
    case 'KeyR': restart(); break;
    case 'KeyN': nextLevel(); break;
    case 'KeyP': toggleAutopilot(); break;
    case 'KeyM': newMaze(); break;
    default: return;
  }
  event.preventDefault();
}

// The page's tilt, (right, up) in milli-g: the joystick while dragged, else
// the keys while held, else the phone (if switched on), else flat.
function tilt() {
  if (stick.active) {
    const dx = stick.x - stick.x0;
    const dy = stick.y - stick.y0;
    const d = Math.hypot(dx, dy);
    const scale = STICK_MAX_MG / STICK_RADIUS_PX / Math.max(1, d / STICK_RADIUS_PX);
    return [Math.round(dx * scale), Math.round(-dy * scale)];
  }
  if (keys.size) {
    const right = (keys.has('right') - keys.has('left')) * KEY_TILT_MG;
    const up = (keys.has('up') - keys.has('down')) * KEY_TILT_MG;
    return [right, up];
  }
  if (orientation.on) return [orientation.right, orientation.up];
  return [0, 0];
}

// Lets go of everything held (keys, the joystick's finger or mouse): at a level
// change, so that a key still down at a win does not tilt the next level from
// its first frame. The next press (or drag) takes hold again.
function releaseInput() {
  keys.clear();
  if (stick.active) {
    stick.active = false;
    const canvas = $('board');
    canvas.classList.remove('dragging');
    if (stick.pointerId != null && canvas.hasPointerCapture?.(stick.pointerId)) {
      canvas.releasePointerCapture(stick.pointerId);
    }
  }
}

function setupStick(canvas) {
  canvas.addEventListener('pointerdown', (e) => {
    stick.active = true;
    stick.pointerId = e.pointerId;
    stick.x0 = stick.x = e.clientX;
    stick.y0 = stick.y = e.clientY;
    canvas.setPointerCapture(e.pointerId);
    canvas.classList.add('dragging');
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!stick.active) return;
    stick.x = e.clientX;
    stick.y = e.clientY;
  });
  const end = () => {
    stick.active = false;
    canvas.classList.remove('dragging');
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
}

// The phone's orientation as a tilt: gamma (left/right) and beta (front/back),
// relative to how it was held when switched on, turned with the screen.
function onOrientation(e) {
  if (e.beta == null || e.gamma == null) return;
  const angle = (screen.orientation && screen.orientation.angle) || 0;
  if (!orientation.neutral) orientation.neutral = { beta: e.beta, gamma: e.gamma };
  const rad = Math.PI / 180;
  // Right edge down: gamma > 0; top edge raised (towards the player): beta > 0.
  const gx = Math.sin((e.gamma - orientation.neutral.gamma) * rad) * 1000;
  const gy = -Math.sin((e.beta - orientation.neutral.beta) * rad) * 1000;
  // The screen turned by `angle` (counter-clockwise) from the phone's natural
  // orientation: its right is the phone's bottom at 90°, its up the phone's right.
  const a = angle * rad;
  const right = gx * Math.cos(a) - gy * Math.sin(a);
  const up = gx * Math.sin(a) + gy * Math.cos(a);
  const clamp = (v) => Math.round(Math.max(-ORIENTATION_MAX_MG, Math.min(ORIENTATION_MAX_MG, v)));
  orientation.right = clamp(right);
  orientation.up = clamp(up);
}

async function toggleOrientation() {
  const button = $('orientation');
  if (orientation.on) {
    orientation.on = false;
    window.removeEventListener('deviceorientation', onOrientation);
    button.setAttribute('aria-pressed', 'false');
    return;
  }
  if (typeof DeviceOrientationEvent === 'undefined') {
    status('this browser has no orientation sensor');
    return;
  }
  // iOS asks the user, and only from a click.
  if (typeof DeviceOrientationEvent.requestPermission === 'function') {
    try {
      if ((await DeviceOrientationEvent.requestPermission()) !== 'granted') {
        status('tilt permission refused');
        return;
      }
    } catch (err) {
      status(`tilt permission: ${err.message}`);
      return;
    }
  }
  orientation.on = true;
  orientation.neutral = null;
  window.addEventListener('deviceorientation', onOrientation);
  button.setAttribute('aria-pressed', 'true');
  status('hold the phone as level, then tilt');
}

// --- the game loop ---------------------------------------------------------------

// One game frame: the step the animation loop and the test's fast-forward share.
function frame() {
  const [right, up] = tilt();
  w.set_tilt(right, up);
  const t0 = performance.now();
  const flags = w.tick();
  costs[costCount++ % COST_WINDOW] = performance.now() - t0;
  followStorey();
  if (flags & TICK_FINISHED) finished();
  if (flags & TICK_NEW_ATTEMPT) newAttempt();
  return flags;
}

// The followed marble's storey after a frame: a drop to a lower one starts the
// floor flash (the LED matrix's, `render::drop_glow`).
function followStorey() {
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

let last = null;
let acc = 0;

// Plays the game frames `elapsed` ms of wall time are worth: the accumulator
// keeps the remainder, so any refresh rate gives 128 frames a second.
function advance(elapsed) {
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

function loop(now) {
  if (last !== null && running) advance(now - last);
  last = now;
  draw();
  requestAnimationFrame(loop);
}

function finished() {
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

function bestKey() {
  return `marble-rolling.best.${w.level_is_custom() ? 'editor:' : ''}${levelName()}`;
}

// --- the ghost ------------------------------------------------------------------

// Where the level's ghost is kept: by stepper (a run replays only on the one
// it was played with) and level name (a generated maze's holds its seed, size,
// storeys and difficulty).
function ghostKey() {
  const stepping = w.stepping_events() ? 'events' : 'fixed';
  return `marble-rolling.ghost.${stepping}.${w.level_is_custom() ? 'editor:' : ''}${levelName()}`;
}

function storedGhost() {
  try {
    const entry = JSON.parse(localStorage.getItem(ghostKey()));
    return entry && typeof entry.ghost === 'string' && Number.isFinite(entry.clock) ? entry : null;
  } catch {
    return null;
  }
}

function toBase64(bytes) {
  let binary = '';
  for (let i = 0; i < bytes.length; i += 0x8000) {
    binary += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(binary);
}

function fromBase64(text) {
  const binary = atob(text);
  const bytes = new Uint8Array(binary.length);
  for (let i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
  return bytes;
}

// The win just finished, kept as the level's ghost if it is the first or
// faster on the clock than the one kept (the autopilot's runs too: racing its
// line is a fair challenge, and the HUD says whose run it is). True if kept.
function saveGhost() {
  const len = w.finished_ghost_len();
  if (!len) return false;
  const clock = w.finished_clock();
  const kept = storedGhost();
  if (kept && kept.clock <= clock) return false;
  const bytes = new Uint8Array(w.memory.buffer, w.record_ptr(), len);
  const entry = { clock, frames: w.finished_frames(), by: w.autopilot() ? 'autopilot' : 'you', ghost: toBase64(bytes) };
  try {
    localStorage.setItem(ghostKey(), JSON.stringify(entry));
  } catch (e) {
    // Storage full (or off): the run is not kept, the game goes on.
    return false;
  }
  return true;
}

// Hands the level's stored ghost to the module (it checks that its replay
// wins this level on its hash; one that does not is forgotten), or drops the
// one on show if there is none.
function showGhost() {
  const key = ghostKey();
  const entry = storedGhost();
  if (!entry) {
    w.clear_ghost();
    ghostShown = null;
    return;
  }
  if (w.ghost_active() && ghostShown === `${key} ${entry.ghost}`) return;
  ghostShown = null;
  const bytes = fromBase64(entry.ghost);
  if (bytes.length > w.ghost_capacity()) {
    localStorage.removeItem(key);
    w.clear_ghost();
    return;
  }
  new Uint8Array(w.memory.buffer, w.ghost_in_ptr(), bytes.length).set(bytes);
  const err = w.load_ghost(bytes.length);
  if (err) {
    // From another build or an edited level: the next win replaces it.
    localStorage.removeItem(key);
    console.info(`ghost of ${levelName()} dropped: ${answer(err)}`);
    return;
  }
  ghostShown = `${key} ${entry.ghost}`;
}

function ghostNote() {
  if (!w.ghost_active()) return 'win to leave one';
  const entry = storedGhost();
  const by = entry && entry.by === 'autopilot' ? ' (autopilot)' : '';
  return `${(w.ghost_record(1) / hz).toFixed(2)} s${by}`;
}

// --- generated mazes ------------------------------------------------------------

// Argument `what` of the generated maze in play (0 seed, 1 size, 2 storeys, 3
// difficulty): the export's u32 arrives as a signed i32, so a seed from 2³¹ up
// would read negative.
function mazeArg(what) {
  return w.level_maze(what) >>> 0;
}

// The maze of `seed` (the arguments of `cargo sim -- --generate`; those not
// given take its defaults): true if it plays, else the generator's message.
function playMaze(seed, { size, storeys, difficulty } = {}) {
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
function newMaze() {
  const seed = crypto.getRandomValues(new Uint32Array(1))[0];
  const generated = w.level_is_generated();
  playMaze(seed, {
    storeys: Number($('maze-storeys').value),
    size: generated ? mazeArg(1) : undefined,
    difficulty: generated ? mazeArg(3) : undefined,
  });
}

// The URL says which maze is in play (`?seed=N&storeys=S`, size and
// difficulty when not the defaults), so it can be bookmarked or shared; for
// the other levels it has no query.
function updateUrl() {
  const url = new URL(window.location.href);
  url.search = '';
  if (w.level_is_generated()) {
    url.searchParams.set('seed', String(mazeArg(0)));
    url.searchParams.set('storeys', String(mazeArg(2)));
    if (mazeArg(1) !== w.default_maze_size()) url.searchParams.set('size', String(mazeArg(1)));
    if (mazeArg(3) !== w.default_maze_difficulty()) url.searchParams.set('difficulty', String(mazeArg(3)));
  }
  if (url.href !== window.location.href) history.replaceState(null, '', url);
}

// The maze's arguments a URL may give besides its seed.
const MAZE_PARAMS = ['size', 'storeys', 'difficulty'];

// The maze a URL asks for: `seed` (0 ..= 4294967295) and the other arguments
// as whole numbers; none if the URL names none; an error message if
// malformed, or if it gives them without a seed (no maze to play).
function mazeFromUrl() {
  const params = new URLSearchParams(window.location.search);
  if (!params.has('seed')) {
    const given = MAZE_PARAMS.filter((name) => params.has(name));
    if (!given.length) return null;
    const args = given.map((name) => `${name}=${params.get(name)}`).join('&');
    return { error: `${args} in the URL needs a seed (?seed=N&${args}): playing the first level` };
  }
  const whole = (name, max) => {
    if (!params.has(name)) return undefined;
    const text = params.get(name);
    const n = Number(text);
    if (!/^\d+$/.test(text) || n > max) throw new Error(`${name}=${text} in the URL is not a whole number 0 ..= ${max}`);
    return n;
  };
  try {
    return {
      seed: whole('seed', 0xffffffff),
      size: whole('size', 255), storeys: whole('storeys', 255), difficulty: whole('difficulty', 255),
    };
  } catch (e) {
    return { error: e.message };
  }
}

// A new level or a restart: its geometry, the picker, the best time; held
// input is let go at a new level.
function newAttempt() {
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
  boardCache = null;
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
function kindsOf(s) {
  if (!level.kinds[s]) {
    const { nx, nz } = level;
    const kinds = new Uint8Array(nx * nz);
    for (let k = 0; k < nz; k++) for (let i = 0; i < nx; i++) kinds[k * nx + i] = w.tile_kind(i, k, s);
    level.kinds[s] = kinds;
  }
  return level.kinds[s];
}

// The height of storey `s`'s floor top, mm (eq. 5: y' = s pitches).
function storeyFloorMm(s) {
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
function placements() {
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

function restart() {
  w.restart();
  newAttempt();
  status('');
}

// The next built-in level; on a generated maze (which plays alone, and again
// after a win) a new maze like it.
function nextLevel() {
  if (w.level_is_generated()) {
    newMaze();
    return;
  }
  w.next_level();
  newAttempt();
  status('');
}

function setStepping(events) {
  w.set_stepping(events ? 1 : 0);
  newAttempt();
  status(`${events ? 'event' : 'fixed'} stepping: ${level.name} from its start`);
}

function toggleAutopilot() {
  w.set_autopilot(w.autopilot() ? 0 : 1);
  $('autopilot').setAttribute('aria-pressed', String(!!w.autopilot()));
}

function status(text) {
  $('status').textContent = text;
}

// --- drawing --------------------------------------------------------------------

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
function fitBoard() {
  $('board-wrap').style.setProperty('--maze-aspect', String(level.edges[level.nz] / level.edges[level.nx]));
}

// Gap between storey maps side by side, in tile pitches.
const MAP_GAP_PITCHES = 0.5;

// mm → canvas px for `maps` storey maps side by side, centred in the canvas;
// map m starts `stride` px after map m - 1.
function view(canvas, maps) {
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

function drawHud() {
  const frames = w.clock_frames();
  const where = w.level_is_custom() ? ' (editor)' : w.level_is_generated() ? ' (generated)' : ` (${w.level_index() + 1})`;
  $('hud-level').textContent = `${level.name}${where}`;
  // The level clock: it starts at the first tilt that rolls the marble.
  $('hud-time').textContent = frames || w.phase() !== 0
    ? `${(frames / hz).toFixed(1)} / ${w.time_limit_s()} s`
    : `tilt to start (${w.time_limit_s()} s)`;
  $('hud-stepping').textContent = w.stepping_events() ? 'events' : 'fixed';
  // The reading is the board's (x right, z towards the player): shown as the page's tilt.
  $('hud-tilt').textContent = `→ ${-w.reading_x()} mg, ↑ ${w.reading_z()} mg`;
  // The mean: Chromium's clock ticks in 5 µs or coarser, about a frame's cost.
  const n = Math.min(costCount, COST_WINDOW);
  if (n > 0) {
    let sum = 0;
    for (let i = 0; i < n; i++) sum += costs[i];
    $('hud-cost').textContent = `${((sum / n) * 1000).toFixed(1)} µs`;
  }
}

function draw() {
  if (!level) return;
  drawBoard();
  drawLeds();
  drawHud();
}

// --- the editor -----------------------------------------------------------------

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

function setupEditor() {
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

// --- Download for micro:bit ------------------------------------------------------

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
async function downloadHex() {
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
  if (n < 0) {
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
function toggleEditor(open) {
  const editor = $('editor');
  const show = open ?? editor.hidden;
  editor.hidden = !show;
  $('editor-toggle').setAttribute('aria-expanded', String(show));
  if (show) editor.scrollIntoView({ block: 'nearest' });
}

// --- start ----------------------------------------------------------------------

// Read-only views and a fast-forward for the browser test (web/test); the
// fast-forward runs the same `frame()` as the animation loop.
function testHooks() {
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
  window.marbleTest = {
    levels: () => Array.from({ length: w.level_count() }, (_, i) => answer(w.builtin_name(i))),
    setRunning(on) { running = !!on; },
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
      const maze = boardCache.canvas.getContext('2d');
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
      acc = 0;
      let played = 0;
      for (let i = 0; i < Math.round(refreshHz * seconds); i++) played += advance(1000 / refreshHz);
      return played;
    },
    // Game frames played by one animation frame that comes `ms` late.
    stall(ms) {
      acc = 0;
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

async function main() {
  try {
    w = await load();
  } catch (e) {
    $('fatal').hidden = false;
    $('fatal').textContent = `cannot load the game: ${e.message}`;
    throw e;
  }
  if (!w.init()) throw new Error('the game could not be set up');
  hz = w.frame_hz();
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
  $('restart').addEventListener('click', restart);
  $('next').addEventListener('click', nextLevel);
  $('autopilot').addEventListener('click', toggleAutopilot);
  $('new-maze').addEventListener('click', () => { newMaze(); $('new-maze').blur(); });
  $('maze-storeys').addEventListener('change', () => $('maze-storeys').blur());
  $('orientation').addEventListener('click', toggleOrientation);
  window.addEventListener('keydown', (e) => onKey(e, true));
  window.addEventListener('keyup', (e) => onKey(e, false));
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
