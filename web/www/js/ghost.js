// The ghost: each level's best win kept in localStorage and handed back to the
// module at the next attempt, which replays it beside the player.

import { answer, hz, levelName, w } from './core.js';

// The ghost marble's opacity: dimmer than the live one, which is drawn opaque.
export const GHOST_ALPHA = 0.4;

// The stored ghost the module plays (its storage key and base64), so that a
// restart does not load and check it again.
let ghostShown = null;

// Where the level's ghost is kept: by stepper (a run replays only on the one
// it was played with) and level name (a generated maze's holds its seed, size,
// storeys and difficulty).
export function ghostKey() {
  const stepping = w.stepping_events() ? 'events' : 'fixed';
  return `marble-rolling.ghost.${stepping}.${w.level_is_custom() ? 'editor:' : ''}${levelName()}`;
}

export function storedGhost() {
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
export function saveGhost() {
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
export function showGhost() {
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

export function ghostNote() {
  if (!w.ghost_active()) return 'win to leave one';
  const entry = storedGhost();
  const by = entry && entry.by === 'autopilot' ? ' (autopilot)' : '';
  return `${(w.ghost_record(1) / hz).toFixed(2)} s${by}`;
}
