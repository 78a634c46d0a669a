// What every part of the page shares: the wasm module's exports (`w`, loaded
// by hand: web/src/lib.rs says why there is no wasm-bindgen glue), the game's
// frame rate, the answers and text buffers the module shares with the page,
// and the status line.

export const PHASES = ['playing', 'won', 'fell', 'timeout'];
export const PHASE_WON = 1;
export const TICK_FINISHED = 1;
export const TICK_NEW_ATTEMPT = 2;

export const $ = (id) => document.getElementById(id);
const encoder = new TextEncoder();
export const decoder = new TextDecoder();

export let w; // the module's exports (a live binding for the other modules)
export let hz; // game frames per second

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
export function answer(len) {
  return decoder.decode(new Uint8Array(w.memory.buffer, w.out_ptr(), len));
}

// Puts `text` in the module's text buffer; returns the byte count to pass on.
// A text longer than the buffer (no level is) hands over the whole lines that
// fit, marked as cut: the module then shows the first error in them (a grid
// over the size limit says so on its first rows), else the length.
export function putText(text) {
  const cap = w.text_capacity();
  const dst = new Uint8Array(w.memory.buffer, w.text_ptr(), cap);
  const { read, written } = encoder.encodeInto(text, dst);
  if (read === text.length) return written;
  const fits = text.slice(0, read);
  const lines = encoder.encodeInto(fits.slice(0, fits.lastIndexOf('\n') + 1), dst);
  return lines.written | w.text_cut();
}

export function hex(u64) {
  return BigInt.asUintN(64, BigInt(u64)).toString(16).padStart(16, '0');
}

export function levelName() {
  return answer(w.level_name());
}

export function status(text) {
  $('status').textContent = text;
}

// Loads the module: `w` from here on.
export async function loadModule() {
  w = await load();
}

// Sets the game up (after loadModule): `hz` from here on.
export function setUp() {
  if (!w.init()) throw new Error('the game could not be set up');
  hz = w.frame_hz();
}
