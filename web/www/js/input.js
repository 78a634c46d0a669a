// The tilt the page feeds the game: held keys, a mouse or finger joystick on
// the maze, or the phone's orientation; and the keys that act (restart, next
// level, autopilot, a new maze).

import { $, status } from './core.js';

// Held keys tilt the board this far (milli-g, per axis): enough to roll
// briskly, well short of the 500 mg the terminal's keys reach.
const KEY_TILT_MG = 300;
// The joystick's full deflection (px from where the drag began) and the tilt it gives.
export const STICK_RADIUS_PX = 80;
export const STICK_MAX_MG = 500;
// The phone's tilt is clamped to this (a phone held at 40° would give 640 mg).
const ORIENTATION_MAX_MG = 600;

export const keys = new Set(); // held tilt keys: 'left', 'right', 'up', 'down'
export const stick = { active: false, x0: 0, y0: 0, x: 0, y: 0 };
export const orientation = { on: false, neutral: null, right: 0, up: 0 };

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

// A key pressed or released: a tilt key held or let go, Space levels
// everything, and a key of `commands` (code → action) runs its action.
export function onKey(event, down, commands) {
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
  if (event.code === 'Space') {
    keys.clear();
    stick.active = false;
    orientation.neutral = null;
  } else if (commands[event.code]) {
    commands[event.code]();
  } else {
    return;
  }
  event.preventDefault();
}

// The page's tilt, (right, up) in milli-g: the joystick while dragged, else
// the keys while held, else the phone (if switched on), else flat.
export function tilt() {
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
export function releaseInput() {
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

export function setupStick(canvas) {
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

export async function toggleOrientation() {
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
