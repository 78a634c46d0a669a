// A race against another page (or any board the relay reaches): the module
// plays the round (web/src/race.rs, the micro:bit v2's RaceRound), this file
// carries its packets through `cargo web`'s relay (`GET /race?ch=N&id=ID&
// out=…`, xtask/src/race_relay.rs) and draws it. A browser has no UDP and no
// radio, so the server in the middle is the channel: every page on a relay
// channel hears the others, and the race protocol does the rest.

import { $, hex, hz, status, w } from './core.js';
import { tilt } from './input.js';
import { ghostNote } from './ghost.js';

// Frames between two calls to the relay (32 calls a second at most: the
// protocol sends a packet every 4 frames).
const POLL_EVERY = 4;
// The most packets a call carries (the relay takes 16).
const MOST_OUT = 16;
export const STATES = ['none', 'looking', 'countdown', 'racing', 'waiting', 'won', 'lost', 'draw', 'again', 'stopped'];

let race = null; // { channel, id, outbox, inFlight, frames, state, autopilot }
let command = 0; // the button pressed since the last race frame

export function racing() {
  return race !== null;
}

function freshId() {
  const a = new Uint32Array(1);
  do crypto.getRandomValues(a); while (a[0] === 0);
  return a[0];
}

function toHex(bytes) {
  return Array.from(bytes, (b) => b.toString(16).padStart(2, '0')).join('');
}

function fromHex(text) {
  const bytes = new Uint8Array(text.length >> 1);
  for (let i = 0; i < bytes.length; i++) bytes[i] = parseInt(text.slice(2 * i, 2 * i + 2), 16);
  return bytes;
}

// Races on relay channel `channel` as a new board; `autopilot` (the browser
// test): null, or the frames of a flat board before the autopilot plays.
export function startRace(channel, autopilot = null) {
  const id = freshId();
  w.race_start(id, autopilot === null ? 0 : 1, autopilot ?? 0);
  race = { channel, id, outbox: [], inFlight: false, frames: 0, state: 'looking', autopilot };
  $('race').setAttribute('aria-pressed', 'true');
  status(`race: looking for an opponent on channel ${channel} (board ${id.toString(16)})`);
}

export function stopRace() {
  w.race_stop();
  race = null;
  $('race').setAttribute('aria-pressed', 'false');
  // Back to the game: its ghost line.
  $('hud-ghost').textContent = ghostNote();
  status('');
}

export function toggleRace() {
  if (racing()) {
    stopRace();
  } else {
    const channel = Math.max(0, Math.min(65535, Number($('race-channel').value) || 0));
    startRace(channel);
  }
  $('race').blur();
}

// One call to the relay: the packets sent since the last, the others' back.
async function poll() {
  const r = race;
  r.inFlight = true;
  const out = r.outbox.splice(0, MOST_OUT).join('.');
  try {
    const reply = await fetch(`/race?ch=${r.channel}&id=${r.id.toString(16)}&out=${out}`, { cache: 'no-store' });
    const text = await reply.text();
    if (reply.ok && race === r) {
      for (const packet of text.split('.').filter(Boolean)) {
        const bytes = fromHex(packet);
        new Uint8Array(w.memory.buffer, w.race_in_ptr(), bytes.length).set(bytes);
        w.race_receive(bytes.length);
      }
    }
  } catch {
    // The server is gone or slow: the packets are lost, the protocol repeats them.
  } finally {
    r.inFlight = false;
  }
}

// Restart (1: A, race again once your run is over) or Next level (2: B,
// stop then), for the next race frame.
export function raceCommand(c) {
  command = c;
}

// One race frame.
export function raceFrame() {
  const [right, up] = tilt();
  const state = STATES[w.race_tick(right, up, command)];
  command = 0;
  const n = w.race_transmit();
  if (n) race.outbox.push(toHex(new Uint8Array(w.memory.buffer, w.race_out_ptr(), n)));
  if (race.outbox.length > 4 * MOST_OUT) race.outbox.splice(0, race.outbox.length - 4 * MOST_OUT);
  race.frames++;
  if (!race.inFlight && race.frames % POLL_EVERY === 0) poll();
  if (state !== race.state) {
    race.state = state;
    said(state);
  }
  if (state === 'again') {
    startRace(race.channel, race.autopilot);
  } else if (state === 'stopped') {
    stopRace();
  }
}

function said(state) {
  const messages = {
    countdown: 'race: paired, get ready',
    racing: 'race: go!',
    waiting: 'race: your run is over; waiting for your opponent',
    won: 'race: you won! (Restart races again, Next level stops)',
    lost: 'race: you lost (Restart races again, Next level stops)',
    draw: 'race: a draw (Restart races again, Next level stops)',
  };
  if (messages[state]) status(messages[state]);
}

// The HUD's ghost line names the opponent while a race is on.
function opponentNote() {
  const peer = w.race_opponent() >>> 0;
  if (!peer) return 'race: looking for an opponent';
  if (w.race_silent()) return `race: board ${peer.toString(16)}, silent: you race alone`;
  if (race.state !== 'racing') return `race: board ${peer.toString(16)}`;
  const behind = Math.max(0, w.race_frames(0) - w.race_frames(1)) / hz;
  return `race: board ${peer.toString(16)}, drawn ${behind.toFixed(2)} s behind`;
}

// The race's matrix (the whole maze, the opponent dimmer) on the board's
// canvas, and on the LEDs.
export function drawRace() {
  if (!race) return;
  const side = w.race_picture_side();
  const pixels = new Uint8Array(w.memory.buffer, w.race_picture(), side * side).slice();
  for (const id of ['board', 'leds']) {
    const canvas = $(id);
    const dpr = window.devicePixelRatio || 1;
    canvas.width = Math.max(1, Math.round(canvas.clientWidth * dpr));
    canvas.height = Math.max(1, Math.round(canvas.clientHeight * dpr));
    const g = canvas.getContext('2d');
    g.fillStyle = '#0c0d10';
    g.fillRect(0, 0, canvas.width, canvas.height);
    const pitch = Math.min(canvas.width, canvas.height) / side;
    for (let y = 0; y < side; y++) {
      for (let x = 0; x < side; x++) {
        const v = pixels[y * side + x] / 15;
        g.fillStyle = v > 0 ? `rgb(${Math.round(90 + 165 * v)},${Math.round(20 + 60 * v)},20)` : '#2a1c1a';
        g.beginPath();
        g.arc((x + 0.5) * pitch, (y + 0.5) * pitch, pitch * 0.3, 0, 2 * Math.PI);
        g.fill();
      }
    }
  }
  $('hud-ghost').textContent = opponentNote();
  $('hud-level').textContent = 'race';
  $('hud-time').textContent = `${(w.race_frames(0) / hz).toFixed(1)} s`;
}

// The browser test's view of the race.
export function raceState() {
  if (!race) return null;
  return {
    state: race.state,
    id: race.id,
    opponent: w.race_opponent() >>> 0,
    frames: w.race_frames(0),
    replayFrames: w.race_frames(1),
    hash: hex(w.race_hash(0)),
    replayHash: hex(w.race_hash(1)),
    verified: ['no', 'yes', 'wrong'][w.race_verified()],
    ghostLine: $('hud-ghost').textContent,
  };
}
