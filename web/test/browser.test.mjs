// The browser test of `cargo web`'s page, in Debian's Chromium (headless),
// driven by playwright-core (which downloads no browser). Run it with
// `cargo xtask web-test`, which builds the module, serves it on a free port and
// passes MARBLE_WEB_URL; run on its own (`node browser.test.mjs`) it starts
// `cargo xtask web --port 0` itself.
//
// It checks: the page loads gzipped, with event stepping, and the wasm game
// runs; one line says what the goal is and the goal is drawn in its green;
// arrow keys, WASD, the mouse joystick and the phone's orientation roll
// the marble the right way; the clock waits for the first roll; a won level's
// best time lands in localStorage and in the panel at once, and its message
// names the level, as a fall's and a time-up's do (an untouched one says so);
// a key, the mouse or a finger held through a win does not
// tilt the next level; on both steppings the autopilot ends every built-in
// level with the state hash `cargo sim -- --level NAME --autopilot --json
// --stepping STEPPING` prints (computed here, at test time), the tile drawn
// under every marble in every frame of those runs is never a wall (the storey
// check), and each win's ghost replays beside the next attempt to its hash; a
// broken level pasted in the editor shows the parser's line:column message,
// the same as `cargo sim -- --check` (a bad tile, a negative time limit, grids
// of 200 and 400 tiles a side); "Download for micro:bit" saves the served
// universal hex with the edited level in both boards' levels regions (the
// Foundation's library reads it, the region decodes to the level's text, the
// rest is as served; with MARBLE_WEB_SAME_AS=HEX,LEVEL, LEVEL's download is
// HEX, `cargo xtask hex --level LEVEL`'s file), says what is wrong when the
// page is served without the .hex or with a broken one, and refuses, saying why, a level too large for any
// micro:bit and one too long for the region; a generated maze has `cargo sim --
// --generate SEED --print-level`'s text and the autopilot wins it with cargo
// sim's hash, the URL's seed plays it, "New maze", `n` and "Next level" put a
// new seed in the URL, `?storeys=9` without a seed is refused with why, and its
// ghost is drawn dimmer and replays to the record's hash; a ghost waits for
// the player's first tilt and races on the player's clock; it writes
// screenshots (two-floors after the drop, a ghost, a phone's viewport) and
// measures the per-frame cost with performance.now(), with a ghost too; two
// pages race through the server's relay to mirrored verdicts, each replay on
// the other's state hash, each naming the other on its ghost line.

import { spawn, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync, mkdirSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
// The micro:bit Foundation's own reader of universal hexes (the version
// `cargo xtask hex --check` pins): the downloaded file is judged by it, not by ours.
import universalHex from '@microbit/microbit-universal-hex';

const ROOT = process.env.MARBLE_ROOT ?? resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const CARGO = process.env.CARGO ?? 'cargo';
const SCREENSHOT = process.env.MARBLE_WEB_SCREENSHOT ?? join(ROOT, 'target/web/web.png');
// Two-floors after the drop, and the page on a phone's screen.
const STOREY_SHOT = join(dirname(SCREENSHOT), 'two-floors.png');
const DROP_SHOT = join(dirname(SCREENSHOT), 'two-floors-drop.png');
const PHONE_SHOT = join(dirname(SCREENSHOT), 'phone.png');
// The steppings the page can run, the default first.
const STEPPINGS = ['events', 'fixed'];
// Tile kinds in the page's draw list (web/src/page_state.rs, tile_kind).
const KIND_NAMES = ['floor', 'wall', 'hole', 'goal', 'start', 'outside'];
// Chromium as the machine's closed network needs it: no background
// connections (they are refused, many at a time), no GPU, no sandbox (root).
const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
];

// An open room: the marble can roll every way from its start.
const OPEN_FIELD = `name: open-field
effects: rolling, friction
time_limit_s: 60
---
###########
#.........#
#.........#
#.........#
#.........#
#....S....#
#.........#
#.........#
#.........#
#........G#
###########
`;
// Two marbles, one on each storey: the board shows both storeys side by side.
const SPLIT = `name: split
effects: rolling, friction
time_limit_s: 60
---
#########
#S......#
#######.#
#######G#
#########
===
#########
#########
#########
#....S..#
#########
`;
// Held → rolls the marble into the hole: a fall.
const PIT = `name: pit
effects: rolling, friction
time_limit_s: 30
---
#######
#S.O.G#
#######
`;
// A second on the clock: a time-up.
const TIMED = `name: timed
effects: rolling, friction
time_limit_s: 1
---
#########
#.......#
#.......#
#..S....#
#.......#
#......G#
#########
`;
// Generated mazes the page must build as `cargo sim -- --generate SEED --storeys N` does.
const MAZES = [{ seed: 7, storeys: 2 }, { seed: 2026, storeys: 3 }, { seed: 90125, storeys: 1 }];
// Line 4, column 3: a tile the format does not know.
const BROKEN = `name: broken
---
#####
#SxG#
#####
`;

// A time limit below its range: the message gives the range, not "not a number".
const NEGATIVE = `name: negative
time_limit_s: -1
---
#####
#S.G#
#####
`;
// An open room `n` tiles a side, over the format's 127: 200 fits the page's
// text buffer, 400 does not (the page hands over the lines that fit).
function room(n) {
  const wall = '#'.repeat(n);
  const inner = (k) => `#${k === 1 ? 'S' : '.'}${'.'.repeat(n - 5)}${k === n - 2 ? 'G' : '.'}#`;
  const rows = Array.from({ length: n - 2 }, (_, k) => inner(k + 1));
  return `name: room-${n}\n---\n${wall}\n${rows.join('\n')}\n${wall}\n`;
}

// An open room `n` tiles a side (`n` odd), its start and goal on cells: a level.
function openRoom(n) {
  const wall = '#'.repeat(n);
  const rows = Array.from({ length: n - 2 },
    (_, i) => `#${i === 0 ? 'S' : '.'}${'.'.repeat(n - 4)}${i === n - 3 ? 'G' : '.'}#`);
  return `name: open-${n}\n---\n${wall}\n${rows.join('\n')}\n${wall}\n`;
}

// The levels region of each micro:bit (src/board/levels_region.rs: V1, V2)
// and its size, by the universal hex's block type.
const REGIONS = new Map([[0x9900, 0x3f000], [0x9903, 0x7b000]]);
const REGION_SIZE = 4096;

// Each board's flash bytes (address → byte) in a universal hex, as the
// Foundation's library separates it into one Intel HEX per board.
function imagesOf(text) {
  const images = new Map();
  for (const { boardId, hex } of universalHex.separateUniversalHex(text)) {
    const image = new Map();
    let base = 0;
    for (const line of hex.split(/\r?\n/).filter((l) => l.startsWith(':'))) {
      const b = Buffer.from(line.slice(1), 'hex');
      const offset = (b[1] << 8) | b[2];
      const data = b.subarray(4, b.length - 1);
      if (b[3] === 0x04) base = ((data[0] << 8) | data[1]) * 0x10000;
      else if (b[3] === 0x02) base = ((data[0] << 8) | data[1]) * 16;
      else if (b[3] === 0x00 || b[3] === 0x0d) data.forEach((v, i) => image.set(base + offset + i, v));
    }
    images.set(boardId, image);
  }
  return images;
}

// CRC-32 as zlib computes it (the region's header: docs/boards.md).
function crc32(bytes) {
  let crc = ~0;
  for (const byte of bytes) {
    crc ^= byte;
    for (let k = 0; k < 8; k++) crc = (crc >>> 1) ^ (0xedb88320 & -(crc & 1));
  }
  return ~crc >>> 0;
}

// The level texts of the levels region at `at` of `image`, decoded as the
// layout says (magic MRLV, CRC-32 of bytes 8 .. 16 + length, version 1, the
// count, the length, then each text after its 2-byte length), or why not.
function regionTexts(image, at) {
  const bytes = Buffer.from(Array.from({ length: REGION_SIZE }, (_, i) => image.get(at + i) ?? 0xff));
  if (bytes.toString('latin1', 0, 4) !== 'MRLV') return { error: `magic ${bytes.subarray(0, 4).toString('hex')}` };
  const length = bytes.readUInt32LE(12);
  if (16 + length > REGION_SIZE) return { error: `length ${length}` };
  if (crc32(bytes.subarray(8, 16 + length)) !== bytes.readUInt32LE(4)) return { error: 'CRC' };
  if (bytes[8] !== 1) return { error: `version ${bytes[8]}` };
  const texts = [];
  let p = 16;
  for (let i = 0; i < bytes[9]; i++) {
    const n = bytes.readUInt16LE(p);
    texts.push(bytes.toString('utf8', p + 2, p + 2 + n));
    p += 2 + n;
  }
  return p === 16 + length ? { texts } : { error: `entries end at ${p}, the length says ${16 + length}` };
}

let passed = 0;
let failed = 0;
function check(ok, what, detail = '') {
  if (ok) {
    passed++;
    console.log(`ok   ${what}`);
  } else {
    failed++;
    console.log(`FAIL ${what}${detail ? `: ${detail}` : ''}`);
  }
}

function cargo(args, { allowFailure = false } = {}) {
  const run = spawnSync(CARGO, args, { cwd: ROOT, encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  if (run.status !== 0 && !allowFailure) {
    throw new Error(`cargo ${args.join(' ')} failed (${run.status}): ${run.stderr}`);
  }
  return run;
}

// The URL to test: given, or from a `cargo xtask web --port 0` started here.
async function server() {
  if (process.env.MARBLE_WEB_URL) return { url: process.env.MARBLE_WEB_URL, stop() {} };
  const child = spawn(CARGO, ['xtask', 'web', '--port', '0'], {
    cwd: ROOT, stdio: ['ignore', 'pipe', 'inherit'],
  });
  const url = await new Promise((ok, fail) => {
    let out = '';
    child.stdout.on('data', (d) => {
      out += d;
      const m = /serving (http:\/\/\S+)/.exec(out);
      if (m) ok(m[1]);
    });
    child.on('exit', (code) => fail(new Error(`cargo xtask web exited with ${code}`)));
  });
  return { url, stop: () => child.kill() };
}

// `cargo sim`'s arguments for a generated maze.
function mazeArgs({ seed, storeys }) {
  return ['--generate', String(seed), '--storeys', String(storeys)];
}

// Forgets every stored ghost (the page's localStorage).
async function clearGhosts(page) {
  await page.evaluate(() => Object.keys(localStorage)
    .filter((k) => k.startsWith('marble-rolling.ghost.'))
    .forEach((k) => localStorage.removeItem(k)));
}

// What `cargo sim` says of each level's autopilot run with `stepping`, and its level list.
function hostRuns(names, stepping) {
  const list = cargo(['sim', '--', '--list']).stdout;
  const hostNames = [...list.matchAll(/^\s+\d+\.\s+(\S+)/gm)].map((m) => m[1]);
  const runs = names.map((name) => JSON.parse(cargo(
    ['sim', '--', '--level', name, '--autopilot', '--json', '--stepping', stepping]).stdout));
  return { hostNames, runs };
}

async function main() {
  const { url, stop } = await server();
  const profile = mkdtempSync(join(tmpdir(), 'marble-web-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    headless: true,
    args: CHROMIUM_ARGS,
    viewport: { width: 1200, height: 760 },
  });
  try {
    const page = context.pages()[0] ?? (await context.newPage());
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });

    // 1. The page loads, the module runs, the animation loop plays frames.
    await page.goto(url);
    await page.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
    await page.waitForFunction(() => window.marbleState().frames > 16, null, { timeout: 10000 });
    const first = await page.evaluate(() => window.marbleState());
    check(first.name === 'first-roll' && first.phase === 'playing',
      'page loads, the wasm game runs at its frame rate', JSON.stringify(first));
    check(first.stepping === 'events' && await page.inputValue('#stepping') === 'events',
      'the page steps by events by default', first.stepping);
    check(first.clock === 0 && await page.textContent('#hud-time') === 'tilt to start (30 s)',
      'the clock waits for the first roll', `clock ${first.clock}, ${await page.textContent('#hud-time')}`);
    const served = await page.evaluate(() => performance.getEntriesByType('resource')
      .filter((e) => e.name.endsWith('/marble_web.wasm'))
      .map((e) => ({ encoded: e.encodedBodySize, decoded: e.decodedBodySize }))[0]);
    check(served && served.encoded > 0 && served.encoded < served.decoded / 2,
      `the wasm is served gzipped: ${served?.encoded} bytes for ${served?.decoded}`, JSON.stringify(served));
    console.log(`wasm: ${served?.decoded} bytes, ${served?.encoded} bytes gzipped as served`);
    check(await page.isHidden('#editor'), 'the editor waits behind its button');
    // One line says what the goal is, in the first screen, and the goal tile
    // is drawn in the green it names (its swatch is that colour).
    {
      const goal = page.locator('#goal');
      const text = (await goal.textContent()).replace(/\s+/g, ' ').trim();
      const box = await goal.boundingBox();
      const seen = await page.evaluate(() => {
        window.marbleTest.draw();
        const swatch = getComputedStyle(document.querySelector('#goal .swatch')).backgroundColor;
        return { pixel: window.marbleTest.tilePixel(3), swatch, height: window.innerHeight };
      });
      const { pixel } = seen;
      check(/green square/.test(text) && /holes/.test(text) && await goal.isVisible()
        && box.y + box.height <= seen.height
        && pixel && pixel.g > pixel.r + 60 && pixel.g > pixel.b + 60
        && seen.swatch === `rgb(${pixel.r}, ${pixel.g}, ${pixel.b})`,
      `one line in the first screen says what the goal is: "${text}"; the goal tile is drawn in that green, ${seen.swatch}`,
      JSON.stringify({ box, ...seen }));
    }
    const isolated = await page.evaluate(() => window.crossOriginIsolated);
    check(isolated, 'the page is cross-origin isolated (5 µs performance.now())');

    // From here on the test steps the game itself, through the loop's own frame function.
    await page.evaluate(() => window.marbleTest.setRunning(false));

    // The frame rate: the same game speed whatever the screen's refresh rate,
    // and a bounded catch-up after a stall.
    const rates = await page.evaluate(() =>
      [30, 60, 144, 240].map((refresh) => [refresh, window.marbleTest.playAt(refresh, 2)]));
    check(rates.every(([, frames]) => Math.abs(frames - 256) <= 1),
      `2 s of animation frames play 256 game frames at 30, 60, 144 and 240 Hz`, JSON.stringify(rates));
    const stalled = await page.evaluate(() => window.marbleTest.stall(500));
    check(stalled === 8, 'an animation frame 500 ms late catches up 8 frames, no more', `${stalled}`);

    // 2. Keys and the mouse joystick tilt the board the right way.
    await page.click('#editor-toggle');
    await page.fill('#source', OPEN_FIELD);
    await page.click('#play-source');
    await page.evaluate(() => document.activeElement.blur());
    const field = await page.evaluate(() => window.marbleState());
    check(field.custom && field.name === 'open-field', 'the editor plays a pasted level',
      JSON.stringify({ name: field.name, custom: field.custom }));
    const moves = [
      ['ArrowRight', 1, 0], ['ArrowLeft', -1, 0], ['ArrowUp', 0, -1], ['ArrowDown', 0, 1],
      ['d', 1, 0], ['a', -1, 0], ['w', 0, -1], ['s', 0, 1],
    ];
    for (const [key, sx, sz] of moves) {
      await page.keyboard.press('r');
      const before = (await page.evaluate(() => window.marbleState())).marbles[0];
      await page.keyboard.down(key);
      await page.evaluate(() => window.marbleTest.steps(48));
      await page.keyboard.up(key);
      const after = (await page.evaluate(() => window.marbleState())).marbles[0];
      const dx = after.x - before.x;
      const dz = after.z - before.z;
      const along = sx * dx + sz * dz;
      const across = Math.abs(sx ? dz : dx);
      check(along > 2 && across < 0.1 * along, `key ${key} rolls the marble ${
        sx > 0 ? 'right' : sx < 0 ? 'left' : sz < 0 ? 'up' : 'down'}`,
        `moved ${dx.toFixed(2)} mm right, ${dz.toFixed(2)} mm down`);
    }
    {
      await page.keyboard.press('r');
      const box = await page.locator('#board').boundingBox();
      const cx = box.x + box.width / 2;
      const cy = box.y + box.height / 2;
      const before = (await page.evaluate(() => window.marbleState())).marbles[0];
      await page.mouse.move(cx, cy);
      await page.mouse.down();
      await page.mouse.move(cx - 40, cy + 40, { steps: 4 });
      await page.evaluate(() => window.marbleTest.steps(48));
      await page.mouse.up();
      const after = (await page.evaluate(() => window.marbleState())).marbles[0];
      const dx = after.x - before.x;
      const dz = after.z - before.z;
      check(dx < -2 && dz > 2 && Math.abs(Math.abs(dx) - dz) < 0.2 * dz,
        'dragging the mouse down-left rolls the marble down-left',
        `moved ${dx.toFixed(2)} mm right, ${dz.toFixed(2)} mm down`);
    }

    // The phone's orientation (as Chromium would report it): the first event
    // is taken as level, then the right edge down (gamma > 0) rolls it right
    // and the top edge raised (beta > 0) rolls it down the screen.
    await page.click('#orientation');
    // Switching on is asynchronous where the browser asks for permission: the
    // listener is attached once the button says so (CI saw a run whose events
    // came before it, and the marble did not move).
    await page.waitForFunction(
      () => document.querySelector('#orientation').getAttribute('aria-pressed') === 'true');
    for (const [beta, gamma, sx, sz, what] of [[0, 20, 1, 0, 'right'], [20, 0, 0, 1, 'down']]) {
      await page.keyboard.press('r');
      const before = (await page.evaluate(() => window.marbleState())).marbles[0];
      const tilted = await page.evaluate(([b, g]) => {
        const tilt = (beta, gamma) => window.dispatchEvent(
          new DeviceOrientationEvent('deviceorientation', { alpha: 0, beta, gamma }));
        tilt(5, -3);
        tilt(5 + b, -3 + g);
        window.marbleTest.steps(48);
        const input = window.marbleState().input;
        tilt(5, -3);
        return input;
      }, [beta, gamma]);
      const after = (await page.evaluate(() => window.marbleState())).marbles[0];
      const dx = after.x - before.x;
      const dz = after.z - before.z;
      const along = sx * dx + sz * dz;
      const across = Math.abs(sx ? dz : dx);
      check(along > 2 && across < 0.1 * along, `tilting the phone rolls the marble ${what}`,
        `moved ${dx.toFixed(2)} mm right, ${dz.toFixed(2)} mm down; input ${JSON.stringify(tilted)}`);
    }
    await page.click('#orientation');
    await page.waitForFunction(
      () => document.querySelector('#orientation').getAttribute('aria-pressed') === 'false');
    await page.evaluate(() => document.activeElement.blur());

    // A level won by hand: its best time is kept in localStorage.
    // First two seconds of looking: they do not count.
    await page.evaluate(() => { localStorage.clear(); window.marbleTest.select(0); window.marbleTest.steps(256); });
    await page.keyboard.down('ArrowRight');
    const won = await page.evaluate(() => {
      window.marbleTest.steps(30 * 128, true);
      return window.marbleTest.finished();
    });
    const best = await page.evaluate(() => localStorage.getItem('marble-rolling.best.first-roll'));
    check(won.phase === 'won' && best !== null && Math.abs(Number(best) - won.clock / 128) < 0.001,
      'holding the right arrow wins first-roll; the best time (on the clock) is in localStorage',
      `finished ${JSON.stringify(won)}, stored ${best}`);
    check(won.clock > 0 && won.frames - won.clock === 256,
      'the clock started at the first roll, not at the level\'s start', JSON.stringify(won));
    const message = await page.evaluate(() => window.marbleTest.status());
    check(message === `first-roll: won in ${(won.clock / 128).toFixed(2)} s, a new best! · ghost saved`,
      `the win message names its level and time: "${message}"`);
    // The new best is on the panel at once, beside the level it is for.
    const panel = await page.evaluate(() => ({
      best: document.querySelector('#hud-best').textContent, level: document.querySelector('#hud-level').textContent,
    }));
    check(panel.best === `${(won.clock / 128).toFixed(2)} s` && panel.level.startsWith('first-roll'),
      `a new best shows in Best at once: ${panel.level}, best ${panel.best}`, JSON.stringify(panel));

    // The key still held through the win does not tilt the next level: its
    // first frames are flat and its clock does not start.
    const next = await page.evaluate(() => {
      window.marbleTest.steps(2 * 128);
      const state = window.marbleState();
      return { name: state.name, tilt: state.input.tilt, reading: state.input.reading, clock: state.clock };
    });
    await page.keyboard.up('ArrowRight');
    check(next.name === 'corner' && next.tilt[0] === 0 && next.tilt[1] === 0 && next.clock === 0,
      'a key held through the win is let go at the next level', JSON.stringify(next));
    const after = await page.evaluate(() => window.marbleTest.status());
    check(after.startsWith('first-roll: '), `the message still names the level it was for: "${after}"`);

    // The joystick held through a win, with the mouse and then with a finger
    // (Chromium's touch input through the DevTools protocol): let go at the
    // next level as a key is; moving it on does not take hold again.
    {
      const box = await page.locator('#board').boundingBox();
      const cx = box.x + box.width / 2;
      const cy = box.y + box.height / 2;
      const cdp = await context.newCDPSession(page);
      const pointers = {
        mouse: {
          async down() { await page.mouse.move(cx, cy); await page.mouse.down(); await page.mouse.move(cx + 60, cy, { steps: 3 }); },
          async move() { await page.mouse.move(cx + 70, cy + 10, { steps: 2 }); },
          async up() { await page.mouse.up(); },
        },
        finger: {
          async down() {
            await cdp.send('Emulation.setTouchEmulationEnabled', { enabled: true, maxTouchPoints: 1 });
            await cdp.send('Input.dispatchTouchEvent', { type: 'touchStart', touchPoints: [{ x: cx, y: cy, id: 1 }] });
            for (const dx of [20, 40, 60]) {
              await cdp.send('Input.dispatchTouchEvent', { type: 'touchMove', touchPoints: [{ x: cx + dx, y: cy, id: 1 }] });
            }
          },
          async move() {
            await cdp.send('Input.dispatchTouchEvent', { type: 'touchMove', touchPoints: [{ x: cx + 70, y: cy + 10, id: 1 }] });
          },
          async up() {
            await cdp.send('Input.dispatchTouchEvent', { type: 'touchEnd', touchPoints: [] });
            await cdp.send('Emulation.setTouchEmulationEnabled', { enabled: false });
          },
        },
      };
      for (const [what, pointer] of Object.entries(pointers)) {
        await page.evaluate(() => window.marbleTest.select(0));
        await pointer.down();
        const held = await page.evaluate(() => {
          const input = window.marbleState().input;
          window.marbleTest.steps(30 * 128, true);
          return { input, finished: window.marbleTest.finished() };
        });
        const next = await page.evaluate(() => {
          window.marbleTest.steps(128 + 16);
          return window.marbleState();
        });
        await pointer.move();
        const moved = await page.evaluate(() => { window.marbleTest.steps(16); return window.marbleState(); });
        await pointer.up();
        check(held.input.stick && held.input.tilt[0] > 0 && held.finished.phase === 'won'
          && next.name === 'corner' && !next.input.stick && next.input.tilt.join() === '0,0' && next.clock === 0
          && !moved.input.stick && moved.clock === 0,
        `a ${what} holding the joystick through the win is let go at the next level`,
        JSON.stringify({ held, next: { name: next.name, input: next.input, clock: next.clock }, moved: moved.input }));
      }
      await cdp.detach();
    }

    // A loss names its level and time too: a fall, and a time-up.
    {
      await page.evaluate(() => window.marbleTest.editor(true));
      for (const [source, key, hold, words] of [[PIT, 'ArrowRight', 30 * 128, 'fell into a hole after'],
        [TIMED, 'ArrowRight', 24, "time's up after"]]) {
        await page.fill('#source', source);
        await page.click('#play-source');
        await page.evaluate(() => document.activeElement.blur());
        await page.keyboard.down(key);
        const lost = await page.evaluate((n) => {
          const done = window.marbleTest.steps(n, true);
          return { done, finished: window.marbleTest.finished() };
        }, hold);
        await page.keyboard.up(key);
        const finished = lost.done < hold ? lost.finished
          : await page.evaluate(() => { window.marbleTest.steps(60 * 128, true); return window.marbleTest.finished(); });
        const name = /^name: (\S+)/.exec(source)[1];
        const message = await page.evaluate(() => window.marbleTest.status());
        const expected = `${name}: ${words} ${(finished.clock / 128).toFixed(2)} s, again`;
        check(finished.phase === (words.startsWith('fell') ? 'fell' : 'timeout') && finished.clock > 0 && message === expected,
          `a loss message names its level and time: "${message}"`, `expected "${expected}", ${JSON.stringify(finished)}`);
      }
      // Left untouched for its whole limit: the clock never ran, the message
      // says so rather than "after 0.00 s".
      await page.fill('#source', TIMED);
      await page.click('#play-source');
      await page.evaluate(() => document.activeElement.blur());
      const untouched = await page.evaluate(() => {
        window.marbleTest.steps(60 * 128, true);
        return { finished: window.marbleTest.finished(), message: window.marbleTest.status() };
      });
      const expected = "timed: time's up, the marble did not roll in 1 s (the clock starts when it does), again";
      check(untouched.finished.phase === 'timeout' && untouched.finished.clock === 0
        && untouched.finished.frames === 128 && untouched.message === expected,
      `time up on a level nobody tilted says so: "${untouched.message}"`, JSON.stringify(untouched));
    }

    // 3. On both steppings, the autopilot on every built-in level ends with
    // the host's state hash; in every frame of its runs, the tile drawn under
    // each marble (the page's draw list) is never a wall.
    const names = await page.evaluate(() => window.marbleTest.levels());
    for (const stepping of STEPPINGS) {
      console.log(`running cargo sim --stepping ${stepping} for ${names.length} levels…`);
      const { hostNames, runs } = hostRuns(names, stepping);
      check(JSON.stringify(hostNames) === JSON.stringify(names),
        `the page has the host's ${hostNames.length} built-in levels`, `${names} vs ${hostNames}`);
      const set = await page.evaluate((name) => window.marbleTest.stepping(name), stepping);
      check(set === stepping, `the page switches to stepping=${stepping}`, set);
      // Each autopilot win below leaves its level's ghost (none kept from before).
      await clearGhosts(page);
      let matched = 0;
      const ghostMisses = [];
      let storeyFrames = 0;
      const misdrawn = [];
      for (let i = 0; i < names.length; i++) {
        const web = await page.evaluate((index) => {
          window.marbleTest.select(index);
          window.marbleTest.setAutopilot(true);
          const stepping = window.marbleState().stepping;
          const bad = [];
          let frames = 0;
          const storeys = new Set();
          const before = window.marbleTest.finished().count;
          for (let f = 0; f < 4000 * 128; f++) {
            // The draw list as the next draw() would paint it, then the frame.
            const list = window.marbleTest.placements();
            frames++;
            for (const m of list.marbles) {
              storeys.add(m.storey);
              if (m.kind === 1 || m.kind === 5 || list.shown[m.map] !== m.storey) {
                if (bad.length < 3) bad.push({ frame: f, ...m, shown: list.shown });
              }
            }
            window.marbleTest.steps(1);
            if (window.marbleTest.finished().count !== before) break;
          }
          const record = window.marbleTest.finished();
          window.marbleTest.setAutopilot(false);
          return { ...record, stepping, bad, drawn: frames, storeys: [...storeys] };
        }, i);
        const host = runs[i];
        const same = web.level === i && web.phase === host.outcome && web.frames === host.frames
          && web.hash === host.state_hash && web.stepping === stepping && host.stepping === stepping;
        matched += same;
        check(same, `autopilot on ${names[i]} (stepping=${stepping}): ${web.phase} in ${web.frames} frames, state_hash ${web.hash}`,
          `host: ${host.outcome} in ${host.frames} frames (${host.stepping}), state_hash ${host.state_hash}`);
        storeyFrames += web.drawn;
        if (web.bad.length) misdrawn.push(`${names[i]}: ${JSON.stringify(web.bad)}`);
        // The next attempt races that win's ghost: the live game played by the
        // autopilot again (so it neither falls nor restarts before the ghost
        // ends), the ghost fed only its recorded readings.
        const ghost = await page.evaluate((index) => {
          window.marbleTest.select(index);
          const loaded = window.marbleState().ghost;
          window.marbleTest.setAutopilot(true);
          window.marbleTest.steps(4000 * 128, true);
          window.marbleTest.setAutopilot(false);
          return { loaded, end: window.marbleState().ghost, stored: window.marbleTest.storedGhost() };
        }, i);
        const replayed = ghost.loaded && ghost.loaded.frames === ghost.loaded.record.idle && ghost.loaded.clock === 0 && ghost.end
          && ghost.end.phase === 'won' && ghost.end.hash === web.hash && ghost.end.record.hash === web.hash
          && ghost.end.frames === web.frames && ghost.stored?.by === 'autopilot';
        if (!replayed) ghostMisses.push(`${names[i]}: ${JSON.stringify({ ...ghost, stored: ghost.stored && { ...ghost.stored, ghost: `${ghost.stored.ghost.length} chars` } })}`);
        if (/floors/.test(names[i])) {
          check(web.storeys.length > 1, `storey: the autopilot's marble on ${names[i]} is drawn on ${web.storeys.length} storeys`);
        }
      }
      console.log(`state hashes: ${matched}/${names.length} levels match cargo sim (stepping=${stepping})`);
      check(ghostMisses.length === 0,
        `ghost: every built-in level's autopilot win, kept in localStorage, replays beside the next attempt to the win's frames and state hash (stepping=${stepping})`,
        ghostMisses.join('; '));
      check(misdrawn.length === 0,
        `storey: in ${storeyFrames} frames of the autopilot on every built-in level (stepping=${stepping}), `
        + 'each marble is drawn on its own storey, never over a wall', misdrawn.join('; '));
    }
    await page.evaluate(() => window.marbleTest.stepping('events'));

    // Two-floors after the drop: the lower storey on show (and the drop's
    // flash a few frames after it), as the LEDs show it.
    {
      const index = names.indexOf('two-floors');
      const shot = await page.evaluate((i) => {
        window.marbleTest.select(i);
        window.marbleTest.setAutopilot(true);
        let start = window.marbleTest.placements().marbles[0].storey;
        for (let f = 0; f < 60 * 128; f++) {
          window.marbleTest.steps(1);
          const m = window.marbleTest.placements().marbles[0];
          if (m && m.storey < start) break;
        }
        // The flash, a few frames after the drop.
        window.marbleTest.steps(4);
        window.marbleTest.draw();
        return start;
      }, index);
      await page.locator('#board').screenshot({ path: DROP_SHOT });
      console.log(`screenshot: ${DROP_SHOT}`);
      const list = await page.evaluate(() => {
        // Once the flash is over.
        window.marbleTest.steps(60);
        window.marbleTest.draw();
        window.marbleTest.setAutopilot(false);
        return window.marbleTest.placements();
      });
      check(shot === 1 && JSON.stringify(list.shown) === '[0]'
        && list.marbles.every((m) => m.storey === 0 && KIND_NAMES[m.kind] !== 'wall'),
        'storey: two-floors after the drop shows the lower storey, the marble on its floor',
        JSON.stringify({ start: shot, list }));
      await page.locator('#board').screenshot({ path: STOREY_SHOT });
      console.log(`screenshot: ${STOREY_SHOT}`);
    }

    // Marbles on different storeys: both storeys side by side, each marble on its own.
    {
      await page.fill('#source', SPLIT);
      await page.click('#play-source');
      await page.evaluate(() => document.activeElement.blur());
      const split = await page.evaluate(() => {
        window.marbleTest.steps(64);
        window.marbleTest.draw();
        return { name: window.marbleState().name, list: window.marbleTest.placements() };
      });
      const { list } = split;
      check(split.name === 'split' && JSON.stringify(list.shown) === '[1,0]' && list.marbles.length === 2
        && list.marbles.every((m) => list.shown[m.map] === m.storey && m.kind !== 1 && m.kind !== 5),
        'storey: marbles on two storeys are drawn on both storeys side by side, each on its own',
        JSON.stringify(split));
      await page.locator('#board').screenshot({ path: join(dirname(SCREENSHOT), 'split.png') });
    }

    // 4. A broken level: the parser's line:column message, as `cargo sim -- --check` gives it.
    const scratch = mkdtempSync(join(tmpdir(), 'marble-web-level-'));
    const file = join(scratch, 'broken.level');
    writeFileSync(file, BROKEN);
    const host = cargo(['sim', '--', '--check', file], { allowFailure: true });
    rmSync(scratch, { recursive: true, force: true });
    // `FILE:line:column: message`, among cargo's own lines.
    const hostLine = `${host.stdout}\n${host.stderr}`.split('\n').find((l) => l.startsWith(`${file}:`));
    const hostMessage = (hostLine ?? '').slice(file.length + 1);
    const playing = await page.evaluate(() => window.marbleState().name);
    await page.fill('#source', BROKEN);
    const live = await page.textContent('#source-error');
    await page.click('#play-source');
    const shown = await page.textContent('#source-error');
    const still = await page.evaluate(() => window.marbleState().name);
    check(/^4:3: /.test(shown) && shown === hostMessage && live === shown,
      `a broken level shows the parser's message: "${shown}"`, `host: "${hostMessage}", live: "${live}"`);
    check(still === playing, 'the broken level leaves the game playing', `${playing} → ${still}`);
    // More errors in the editor, each as `cargo sim -- --check` words it.
    for (const [source, expected] of [
      [NEGATIVE, '2:15: value out of range: time_limit_s is 1 ..= 3600'],
      [room(200), '3:1: grid larger than 127 tiles'],
      [room(400), '3:1: grid larger than 127 tiles'],
    ]) {
      const scratchDir = mkdtempSync(join(tmpdir(), 'marble-web-level-'));
      const levelFile = join(scratchDir, 'editor.level');
      writeFileSync(levelFile, source);
      const run = cargo(['sim', '--', '--check', levelFile], { allowFailure: true });
      rmSync(scratchDir, { recursive: true, force: true });
      const line = `${run.stdout}\n${run.stderr}`.split('\n').find((l) => l.startsWith(`${levelFile}:`));
      const hostSays = (line ?? '').slice(levelFile.length + 1);
      await page.fill('#source', source);
      const pageSays = await page.textContent('#source-error');
      const name = /^name: (\S+)/.exec(source)[1];
      check(pageSays === expected && hostSays === expected,
        `the editor refuses ${name} (${source.length} characters) as cargo sim -- --check does: "${pageSays}"`,
        `host: "${hostSays}", expected "${expected}"`);
    }

    // 4b. "Download for micro:bit": the served universal hex with the edited
    // level in both boards' levels regions, the rest as served; a level no
    // micro:bit can show and one the region cannot hold are refused, saying why.
    {
      const downloads = [];
      page.on('download', (d) => downloads.push(d));
      const served = await (await fetch(new URL('marble-rolling.hex', url))).text();
      const servedImages = imagesOf(served);
      await page.evaluate(() => window.marbleTest.editor(true));
      await page.fill('#source', SPLIT);
      const [download] = await Promise.all([
        page.waitForEvent('download', { timeout: 20000 }),
        page.click('#download-hex'),
      ]);
      const text = readFileSync(await download.path(), 'ascii');
      const says = await page.textContent('#download-status');
      check(download.suggestedFilename() === 'marble-rolling-split.hex' && /copy it onto the MICROBIT drive/.test(says),
        `Download for micro:bit saves ${download.suggestedFilename()}: "${says}"`);
      const images = imagesOf(text);
      check(universalHex.isUniversalHex(text) && images.has(0x9900) && images.has(0x9903),
        `the Foundation's library takes the download (${text.length} B) for a universal hex with both boards' images`,
        [...images.keys()].map((k) => k.toString(16)).join(', '));
      for (const [board, at] of REGIONS) {
        const image = images.get(board) ?? new Map();
        const region = regionTexts(image, at);
        check(region.texts?.length === 1 && region.texts[0] === SPLIT,
          `the download's ${board.toString(16)} image has the edited level in its levels region at 0x${at.toString(16)}`,
          JSON.stringify(region).slice(0, 200));
        const before = servedImages.get(board) ?? new Map();
        const outside = (a) => a < at || a >= at + REGION_SIZE;
        const changed = [...new Set([...before.keys(), ...image.keys()])]
          .filter((a) => outside(a) && before.get(a) !== image.get(a));
        check(before.size > 10000 && changed.length === 0,
          `the download's ${board.toString(16)} image is the served one outside the region (${before.size} B)`,
          `${changed.length} bytes differ, the first at 0x${changed[0]?.toString(16)}`);
      }
      // Given `cargo xtask hex --level FILE`'s universal hex for the served
      // one (CI keeps it from its .hex step), FILE's download is that file,
      // byte for byte.
      const sameAs = process.env.MARBLE_WEB_SAME_AS;
      if (sameAs) {
        const [hexFile, levelFile] = sameAs.split(',');
        await page.fill('#source', readFileSync(resolve(ROOT, levelFile), 'utf8'));
        const [same] = await Promise.all([
          page.waitForEvent('download', { timeout: 20000 }),
          page.click('#download-hex'),
        ]);
        const ours = readFileSync(await same.path());
        const theirs = readFileSync(resolve(ROOT, hexFile));
        check(ours.equals(theirs),
          `the download of ${levelFile} is ${hexFile} (cargo xtask hex --level), byte for byte (${ours.length} B)`,
          `${ours.length} B against ${theirs.length} B`);
      }
      // A level only the v2 can show: saved, with a warning that names the v1.
      await page.fill('#source', openRoom(31));
      const [wide] = await Promise.all([
        page.waitForEvent('download', { timeout: 20000 }),
        page.click('#download-hex'),
      ]);
      const warned = await page.textContent('#download-status');
      check(wide.suggestedFilename() === 'marble-rolling-open-31.hex'
        && /; a micro:bit v1 cannot show this level: it needs 61 occupancy words of tiles, the micro:bit v1 holds 57 /.test(warned)
        && await page.getAttribute('#download-status', 'class') === 'warn',
      `a level only the v2 can show is saved with a warning: "${warned}"`);
      for (const [source, expected] of [
        [openRoom(61), /^cannot download: too large for a micro:bit: the level needs 233 occupancy words of tiles; the micro:bit v1 holds 57 .*the micro:bit v2 111/],
        [`name: ${'a'.repeat(4100)}\n---\n#####\n#S.G#\n#####\n`,
          /^cannot download: too long for the levels region: the level's text takes 4\d\d\d B there .*the region holds 4096 B$/],
      ]) {
        const saved = downloads.length;
        await page.fill('#source', source);
        await page.click('#download-hex');
        await page.waitForFunction(() => /^cannot/.test(document.querySelector('#download-status').textContent),
          null, { timeout: 10000 });
        const refused = await page.textContent('#download-status');
        check(expected.test(refused) && downloads.length === saved
          && await page.getAttribute('#download-status', 'class') === 'bad',
        `Download for micro:bit refuses ${/^name: (\S{1,12})/.exec(source)[1]}: "${refused}"`);
      }
      // A page served without the .hex, or with a broken one: it says so.
      const lines = served.split('\n');
      lines[2] = lines[2].slice(0, -1) + (lines[2].endsWith('0') ? '1' : '0');
      for (const [what, reply, expected] of [
        ['without the .hex', { status: 404, body: '404 Not Found\n' },
          /^cannot download: this page is served without the micro:bit \.hex \(HTTP 404\); run `cargo xtask hex`, then reload the page$/],
        ['a .hex with a bad checksum on its line 3', { status: 200, body: lines.join('\n') },
          /^cannot download: the served \.hex: line 3: wrong checksum$/],
      ]) {
        const other = await context.newPage();
        await other.route('**/marble-rolling.hex', (route) => route.fulfill({ contentType: 'text/plain', ...reply }));
        await other.goto(url);
        await other.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
        await other.evaluate(() => { window.marbleTest.setRunning(false); window.marbleTest.editor(true); });
        await other.fill('#source', SPLIT);
        await other.click('#download-hex');
        await other.waitForFunction(() => /^cannot/.test(document.querySelector('#download-status').textContent),
          null, { timeout: 10000 });
        const said = await other.textContent('#download-status');
        check(expected.test(said), `served ${what}, Download for micro:bit says so: "${said}"`);
        await other.close();
      }
    }

    // 5. Generated mazes: the page's generator gives `cargo sim -- --generate`'s
    // text for the same seed, and the autopilot wins it with cargo sim's hash.
    for (const maze of MAZES) {
      const what = `maze ${maze.seed} (${maze.storeys} storeys)`;
      const hostText = cargo(['sim', '--', ...mazeArgs(maze), '--print-level']).stdout;
      const made = await page.evaluate((m) => window.marbleTest.mazeText(m.seed, { storeys: m.storeys }), maze);
      check(made.text === hostText && /^name: maze-/.test(hostText),
        `generated: ${what} has the level text of cargo sim -- ${mazeArgs(maze).join(' ')} --print-level`,
        `page: ${JSON.stringify(made).slice(0, 300)}; host: ${JSON.stringify(hostText.slice(0, 200))}`);
      for (const stepping of STEPPINGS) {
        const host = JSON.parse(cargo(['sim', '--', ...mazeArgs(maze), '--autopilot', '--json', '--stepping', stepping]).stdout);
        const web = await page.evaluate(([m, stepping]) => {
          window.marbleTest.stepping(stepping);
          const played = window.marbleTest.playMaze(m.seed, { storeys: m.storeys });
          const state = window.marbleState();
          window.marbleTest.setAutopilot(true);
          window.marbleTest.steps(4000 * 128, true);
          window.marbleTest.setAutopilot(false);
          return { played, name: state.name, maze: state.maze, text: window.marbleTest.sourceText(), ...window.marbleTest.finished() };
        }, [maze, stepping]);
        check(web.played && web.text === hostText && web.maze.seed === maze.seed && web.maze.storeys === maze.storeys
          && web.phase === 'won' && host.outcome === 'won' && web.frames === host.frames && web.hash === host.state_hash,
        `generated: the autopilot wins ${what} (stepping=${stepping}) in ${web.frames} frames, state_hash ${web.hash}, as cargo sim does`,
        `page: ${JSON.stringify({ ...web, text: web.text.length })}; host: ${host.outcome} in ${host.frames} frames, ${host.state_hash}`);
      }
    }
    await page.evaluate(() => window.marbleTest.stepping('events'));
    {
      const made = await page.evaluate(() => [window.marbleTest.mazeText(1, { size: 40 }), window.marbleTest.mazeText(1, { storeys: 5 })]);
      check(/outside 2 \.\.= 15/.test(made[0].error) && /outside 1 \.\.= 4/.test(made[1].error),
        `generated: arguments out of range are refused with their range: "${made[0].error}", "${made[1].error}"`);
    }

    // The ghost of a generated maze: the autopilot's win is kept; the next
    // attempt (the maze again) shows it as a dimmer marble that replays the
    // win to its state hash while the player's marble waits at the start.
    {
      await clearGhosts(page);
      const maze = MAZES[0];
      const run = await page.evaluate((m) => {
        window.marbleTest.playMaze(m.seed, { storeys: m.storeys });
        const before = window.marbleState().ghost;
        window.marbleTest.setAutopilot(true);
        window.marbleTest.steps(4000 * 128, true);
        window.marbleTest.setAutopilot(false);
        const won = window.marbleTest.finished();
        const message = window.marbleTest.status();
        const stored = window.marbleTest.storedGhost();
        // The win's pause, then the next attempt.
        window.marbleTest.steps(128 + 1);
        const next = window.marbleState();
        return { before, won, message, stored: stored && { ...stored, ghost: stored.ghost.length }, next };
      }, maze);
      check(run.before === null && run.won.phase === 'won' && run.stored && run.stored.by === 'autopilot'
        && run.stored.clock === run.won.clock && / · ghost saved$/.test(run.message),
      `ghost: the autopilot's win of maze ${maze.seed} is kept in localStorage (${run.stored?.ghost} base64 characters for ${run.won.frames} frames): "${run.message}"`,
      JSON.stringify(run));
      const next = run.next;
      check(next.generated && next.maze.seed === maze.seed && next.frames <= 1 && next.ghost
        && next.ghost.record.hash === run.won.hash && next.ghost.record.frames === run.won.frames,
      'ghost: the next attempt at the maze loads it', JSON.stringify(next));
      // The player nudges the board (a tap of →) and the ghost sets off with
      // the clock; a third of the way on, it has rolled off from the player's marble.
      await page.evaluate(() => document.activeElement.blur());
      await page.keyboard.down('ArrowRight');
      await page.evaluate(() => window.marbleTest.steps(8));
      await page.keyboard.up('ArrowRight');
      const seen = await page.evaluate((n) => {
        window.marbleTest.steps(n);
        window.marbleTest.draw();
        return { list: window.marbleTest.placements(), contrast: window.marbleTest.contrast(), state: window.marbleState() };
      }, Math.floor(run.won.frames / 3));
      const g = seen.list.ghosts[0];
      const m = seen.list.marbles[0];
      check(g && m && g.alpha < 1 && Math.hypot(g.x - m.x, g.z - m.z) > 2
        && seen.contrast.ghost > 0 && seen.contrast.ghost < seen.contrast.live,
      `ghost: drawn as a dimmer marble (opacity ${g?.alpha}; contrast with the floor ${seen.contrast.ghost} against the live marble's ${seen.contrast.live})`,
      JSON.stringify({ ghosts: seen.list.ghosts, marbles: seen.list.marbles, contrast: seen.contrast }));
      await page.locator('#board').screenshot({ path: join(dirname(SCREENSHOT), 'ghost.png') });
      console.log(`screenshot: ${join(dirname(SCREENSHOT), 'ghost.png')}`);
      // On to the ghost's end, its clock the player's in every frame.
      const end = await page.evaluate((n) => {
        const apart = [];
        for (let f = 0; f < n && window.marbleState().ghost.phase === 'playing'; f++) {
          window.marbleTest.steps(1);
          const state = window.marbleState();
          if (state.phase === 'playing' && state.ghost.phase === 'playing' && state.ghost.clock !== state.clock
            && apart.length < 3) apart.push({ clock: state.clock, ghost: state.ghost.clock });
        }
        return { ...window.marbleState(), apart };
      }, run.won.frames);
      check(end.ghost && end.ghost.phase === 'won' && end.ghost.frames === run.won.frames
        && end.ghost.hash === run.won.hash && end.ghost.clock === run.won.clock && end.apart.length === 0,
      `ghost: the replay of maze ${maze.seed} races on the player's clock and ends won after ${end.ghost?.frames} frames on the record's state hash ${end.ghost?.hash}`,
      JSON.stringify({ ghost: end.ghost, phase: end.phase, clock: end.clock, apart: end.apart, won: run.won }));
      // A broken ghost in storage is dropped, never a fault.
      const broken = await page.evaluate(() => {
        const key = window.marbleTest.ghostKey();
        const entry = JSON.parse(localStorage.getItem(key));
        entry.ghost = btoa('MG\x01\x00garbage');
        localStorage.setItem(key, JSON.stringify(entry));
        window.marbleTest.restartLevel();
        return { ghost: window.marbleState().ghost, kept: localStorage.getItem(key) };
      });
      check(broken.ghost === null && broken.kept === null, 'ghost: a broken stored ghost is dropped from storage', JSON.stringify(broken));
    }

    // The ghost races from the first tilt, as the clock does. Corner after
    // the autopilot's win, picked in the list as a player would, then two
    // seconds of looking: the ghost waits at the start beside the player's
    // marble while the panel says "tilt to start"; the first tilt sets it off,
    // on the player's clock.
    {
      await clearGhosts(page);
      const corner = names.indexOf('corner');
      const won = await page.evaluate((i) => {
        window.marbleTest.select(i);
        window.marbleTest.setAutopilot(true);
        window.marbleTest.steps(4000 * 128, true);
        window.marbleTest.setAutopilot(false);
        const finished = window.marbleTest.finished();
        // The win's pause, then the page moves on.
        window.marbleTest.steps(128 + 1);
        return { finished, message: window.marbleTest.status(), next: window.marbleState().name };
      }, corner);
      await page.selectOption('#level', String(corner));
      const looked = await page.evaluate(() => {
        window.marbleTest.steps(2 * 128);
        window.marbleTest.draw();
        return {
          state: window.marbleState(), list: window.marbleTest.placements(),
          hud: document.querySelector('#hud-time').textContent,
        };
      });
      const { state, list } = looked;
      const [g, m] = [list.ghosts[0], list.marbles[0]];
      check(won.finished.phase === 'won' && / · ghost saved$/.test(won.message) && won.next !== 'corner'
        && state.name === 'corner' && state.clock === 0 && /^tilt to start/.test(looked.hud)
        && state.ghost && state.ghost.phase === 'playing' && state.ghost.clock === 0
        && state.ghost.frames === state.ghost.record.idle && g && m && Math.hypot(g.x - m.x, g.z - m.z) < 0.01,
      `ghost: two seconds after corner is picked, untouched, the ghost waits at the start (${state.ghost?.frames} frames of its own looking played), the panel says "${looked.hud}"`,
      JSON.stringify({ won, hud: looked.hud, ghost: state.ghost, clock: state.clock, g, m }));
      await page.evaluate(() => document.activeElement.blur());
      await page.keyboard.down('ArrowRight');
      const raced = await page.evaluate(() => {
        const apart = [];
        let started = null;
        for (let f = 0; f < 96; f++) {
          window.marbleTest.steps(1);
          const state = window.marbleState();
          if (state.clock > 0 && started === null) started = { frames: state.frames, ghost: state.ghost.frames };
          if (state.ghost.clock !== state.clock && apart.length < 3) apart.push({ clock: state.clock, ghost: state.ghost.clock });
        }
        const list = window.marbleTest.placements();
        return { state: window.marbleState(), started, apart, g: list.ghosts[0] };
      });
      await page.keyboard.up('ArrowRight');
      check(raced.started && raced.apart.length === 0 && raced.state.clock > 0 && raced.g
        && Math.hypot(raced.g.x - g.x, raced.g.z - g.z) > 2,
      `ghost: the first tilt (frame ${raced.started?.frames} of the attempt) sets it off, its clock the player's in every frame (${raced.state.clock} frames on)`,
      JSON.stringify(raced));
    }

    // The seed in the URL plays that maze; the new-maze button picks another
    // and puts it in the URL; a built-in level takes it off again.
    {
      const maze = MAZES[0];
      const hostText = cargo(['sim', '--', ...mazeArgs(maze), '--print-level']).stdout;
      const tab = await context.newPage();
      tab.on('pageerror', (e) => errors.push(e.message));
      await tab.goto(`${url}?seed=${maze.seed}&storeys=${maze.storeys}`);
      await tab.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      const loaded = await tab.evaluate(() => {
        window.marbleTest.setRunning(false);
        return { state: window.marbleState(), text: window.marbleTest.sourceText(), search: window.location.search };
      });
      check(loaded.state.generated && loaded.state.maze.seed === maze.seed && loaded.text === hostText
        && loaded.search === `?seed=${maze.seed}&storeys=${maze.storeys}`,
      `generated: the URL ?seed=${maze.seed}&storeys=${maze.storeys} plays ${loaded.state.name}, cargo sim's maze`,
      JSON.stringify({ ...loaded, text: loaded.text.length }));
      // The largest seed: the page's numbers stay unsigned.
      await tab.goto(`${url}?seed=4294967295&storeys=1`);
      await tab.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      const top = await tab.evaluate(() => ({ state: window.marbleState(), search: window.location.search }));
      check(top.state.name === 'maze-4294967295-6x6x1-d2' && top.state.maze.seed === 4294967295
        && top.search === '?seed=4294967295&storeys=1',
      `generated: the URL's largest seed plays ${top.state.name} and stays in the URL: ${top.search}`,
      JSON.stringify({ maze: top.state.maze, search: top.search }));
      await tab.evaluate(() => window.marbleTest.setRunning(false));
      await tab.selectOption('#maze-storeys', '3');
      await tab.click('#new-maze');
      const fresh = await tab.evaluate(() => ({ state: window.marbleState(), search: window.location.search }));
      const params = new URLSearchParams(fresh.search);
      check(fresh.state.generated && fresh.state.maze.seed !== maze.seed && fresh.state.maze.storeys === 3
        && params.get('seed') === String(fresh.state.maze.seed) && params.get('storeys') === '3'
        && fresh.state.name === `maze-${fresh.state.maze.seed}-6x6x3-d2`,
      `generated: "New maze" plays a new seed and puts it in the URL: ${fresh.search}`, JSON.stringify(fresh));
      // Next level (`n`, or the button) on a generated maze: a new maze like
      // it (a maze plays alone, so moving on had replayed the same one).
      for (const how of ['the key n', 'the Next level button']) {
        const before = await tab.evaluate(() => ({ seed: window.marbleState().maze.seed, text: window.marbleTest.sourceText() }));
        if (how === 'the key n') await tab.keyboard.press('n');
        else await tab.click('#next');
        const after = await tab.evaluate(() => ({
          state: window.marbleState(), text: window.marbleTest.sourceText(), search: window.location.search,
        }));
        const query = new URLSearchParams(after.search);
        check(after.state.generated && after.state.maze.seed !== before.seed && after.text !== before.text
          && after.state.frames === 0 && query.get('seed') === String(after.state.maze.seed) && query.get('storeys') === '3',
        `generated: ${how} on maze ${before.seed} plays a new maze, ${after.state.name} (${after.search})`,
        JSON.stringify({ before: before.seed, after: { ...after, text: after.text.length } }));
      }
      const again = await tab.evaluate(() => window.history.length);
      await tab.selectOption('#level', '2');
      const builtin = await tab.evaluate(() => ({ name: window.marbleState().name, search: window.location.search, history: window.history.length }));
      check(builtin.search === '' && builtin.name === names[2] && builtin.history === again,
        `generated: a built-in level takes the seed off the URL (replaced: history stays ${again} entries long)`, JSON.stringify(builtin));
      const bad = await context.newPage();
      bad.on('pageerror', (e) => errors.push(e.message));
      await bad.goto(`${url}?seed=banana`);
      await bad.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      const refused = await bad.evaluate(() => ({ status: window.marbleTest.status(), name: window.marbleState().name }));
      check(/^seed=banana in the URL is not a whole number/.test(refused.status) && refused.name === 'first-roll',
        `generated: a malformed seed in the URL is refused with why: "${refused.status}"`);
      // A maze's argument without a seed is no maze: said, not ignored.
      await bad.goto(`${url}?storeys=9`);
      await bad.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      const seedless = await bad.evaluate(() => ({ status: window.marbleTest.status(), name: window.marbleState().name }));
      check(seedless.status === 'storeys=9 in the URL needs a seed (?seed=N&storeys=9): playing the first level'
        && seedless.name === 'first-roll',
      `generated: ?storeys=9 without a seed is refused with why: "${seedless.status}"`, JSON.stringify(seedless));
      await bad.close();
      await tab.close();
    }

    // 6. A screenshot: cavern, halfway through the autopilot's run.
    await page.fill('#source', OPEN_FIELD);
    await page.evaluate(() => {
      window.marbleTest.select(6);
      window.marbleTest.setAutopilot(true);
      window.marbleTest.steps(150);
      window.marbleTest.draw();
    });
    mkdirSync(dirname(SCREENSHOT), { recursive: true });
    await page.screenshot({ path: SCREENSHOT, fullPage: true });
    console.log(`screenshot: ${SCREENSHOT}`);

    // A phone's viewport: the maze the page's width, the panel under it, the
    // editor behind its button.
    {
      const phone = await context.newPage();
      await phone.setViewportSize({ width: 390, height: 844 });
      await phone.goto(url);
      await phone.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      await phone.evaluate(() => { window.marbleTest.setRunning(false); window.marbleTest.select(7); window.marbleTest.draw(); });
      const box = await phone.locator('#board').boundingBox();
      const panel = await phone.locator('aside').boundingBox();
      const editorHidden = await phone.isHidden('#editor');
      const viewport = phone.viewportSize();
      check(box.width >= viewport.width - 24 && panel.y >= box.y + box.height && editorHidden,
        `on a phone (390 × 844) the maze is ${Math.round(box.width)} px wide, the panel under it, the editor behind its button`,
        JSON.stringify({ box, panel, editorHidden }));
      // No band: the maze's box is as high as the level's shape asks.
      const filled = await phone.evaluate(() => {
        const c = document.querySelector('#board');
        const g = c.getContext('2d');
        // The share of the canvas's rows that hold maze (not the outside colour) in its middle column.
        const data = g.getImageData(Math.floor(c.width / 2), 0, 1, c.height).data;
        let maze = 0;
        for (let y = 0; y < c.height; y++) {
          const [r, gr, b] = [data[4 * y], data[4 * y + 1], data[4 * y + 2]];
          if (!(r === 0x16 && gr === 0x18 && b === 0x1d)) maze++;
        }
        return maze / c.height;
      });
      check(filled > 0.9, `on a phone the maze fills ${(filled * 100).toFixed(0)} % of the board's height`);
      await phone.screenshot({ path: PHONE_SHOT });
      console.log(`screenshot: ${PHONE_SHOT}`);
      await phone.close();
    }

    // 6b. A race between two pages through the server's relay (GET /race):
    // both autopilots, the second after 40 frames of a flat board; each page
    // names the other on its ghost line while they race, both reach mirrored
    // verdicts, and each replay of the opponent ends on the opponent's own
    // state hash (checked in the page too: verified).
    {
      const racers = [await context.newPage(), await context.newPage()];
      for (const p of racers) {
        p.on('pageerror', (e) => errors.push(e.message));
        p.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
        await p.goto(url);
        await p.waitForSelector('body[data-ready="true"]', { timeout: 20000 });
      }
      await racers[0].evaluate(() => window.marbleRace.start(3, 0));
      await racers[1].evaluate(() => window.marbleRace.start(3, 40));
      const start = Date.now();
      let states = [];
      let named = false;
      while (Date.now() - start < 90000) {
        states = await Promise.all(racers.map((p) => p.evaluate(() => window.marbleRace.state())));
        named ||= states.every((r, i) => r.state === 'racing'
          && r.ghostLine.startsWith(`race: board ${states[1 - i].id.toString(16)}`));
        if (states.every((r) => ['won', 'lost', 'draw'].includes(r.state) && r.verified !== 'no')) break;
        await new Promise((ok) => setTimeout(ok, 100));
      }
      const [a, b] = states;
      const mirrored = { won: 'lost', lost: 'won', draw: 'draw' };
      console.log(`race: ${JSON.stringify(a)} / ${JSON.stringify(b)} after ${((Date.now() - start) / 1000).toFixed(1)} s`);
      check(named, 'race: while two pages race, each one\'s ghost line names the other board');
      check(mirrored[a?.state] === b?.state && a.state === 'won',
        `race: mirrored verdicts, the page whose autopilot did not wait won (${a?.state} / ${b?.state})`);
      check(a?.verified === 'yes' && b?.verified === 'yes' && a.replayHash === b.hash && b.replayHash === a.hash
        && a.opponent === b.id && b.opponent === a.id,
        'race: each replay of the opponent ends on its own state hash, verified in the page', JSON.stringify(states));
      await Promise.all(racers.map((p) => p.close()));
    }

    // 7. The per-frame cost: the autopilot playing the levels over and over
    // from the first (its frames that play, not those that show a result).
    const cost = await page.evaluate(() => {
      window.marbleTest.select(0);
      window.marbleTest.setAutopilot(true);
      window.marbleTest.steps(128);
      window.marbleTest.select(0);
      const game = window.marbleTest.measure(2000);
      const t = [];
      for (let i = 0; i < 200; i++) {
        const t0 = performance.now();
        window.marbleTest.draw();
        t.push(performance.now() - t0);
      }
      t.sort((a, b) => a - b);
      // The same frames raced by a ghost: the autopilot's wins of the first
      // levels kept, then those levels again beside them.
      window.marbleTest.select(0);
      window.marbleTest.steps(6000);
      window.marbleTest.select(0);
      const ghosted = window.marbleState().ghost !== null;
      const ghost = window.marbleTest.measure(2000);
      window.marbleTest.setAutopilot(false);
      return { game, draw_median_us: t[t.length >> 1] * 1000, ghost, ghosted };
    });
    const g = cost.game;
    console.log(`frame cost (autopilot through the levels, ${g.frames} playing frames): median ${g.median_us.toFixed(1)} µs, `
      + `p99 ${g.p99_us.toFixed(1)} µs, max ${g.max_us.toFixed(1)} µs, mean ${g.mean_us.toFixed(1)} µs; `
      + `timed in blocks of ${g.block}: median ${g.block_median_us.toFixed(2)} µs per frame; `
      + `drawing the page: median ${cost.draw_median_us.toFixed(0)} µs`);
    console.log(`frame cost with a ghost replayed beside the game: mean ${cost.ghost.mean_us.toFixed(1)} µs, `
      + `p99 ${cost.ghost.p99_us.toFixed(1)} µs; timed in blocks of ${cost.ghost.block}: median ${cost.ghost.block_median_us.toFixed(2)} µs per frame`);
    check(cost.ghosted && cost.ghost.p99_us < 1e6 / 128, 'ghost: with a ghost beside the game, 99 % of the frames cost less than their 7.8 ms',
      JSON.stringify(cost.ghost));
    // Not the max: on a shared machine a single frame can wait out another process.
    check(g.p99_us < 1e6 / 128, '99 % of the frames cost less than their 7.8 ms', `p99 ${g.p99_us} µs`);

    check(errors.length === 0, 'no errors in the page', errors.join('; '));
  } finally {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
    stop();
  }
  console.log(`web-test: ${passed} passed, ${failed} failed`);
  process.exitCode = failed ? 1 : 0;
}

main().catch((e) => {
  console.error(e);
  process.exitCode = 1;
});
