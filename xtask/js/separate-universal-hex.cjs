// `cargo xtask hex --check`: the micro:bit Foundation's own library splits
// our universal hex, so that the file is judged by the format's authors'
// reading of it rather than by ours. Run as
//   node separate-universal-hex.cjs UNIVERSAL.hex OUT_DIR
// from a folder whose node_modules holds @microbit/microbit-universal-hex;
// writes OUT_DIR/board-<id in hex>.hex for each board and prints
// `<id> <file>` lines. Any error (the library's too) exits non-zero.
'use strict';
const fs = require('fs');
const path = require('path');
const universal = require('@microbit/microbit-universal-hex');

const [file, out] = process.argv.slice(2);
if (!file || !out) {
  console.error('usage: node separate-universal-hex.cjs UNIVERSAL.hex OUT_DIR');
  process.exit(2);
}
const text = fs.readFileSync(file, 'ascii');
if (!universal.isUniversalHex(text)) {
  console.error(`${file}: the library does not take it for a universal hex`);
  process.exit(1);
}
for (const { boardId, hex } of universal.separateUniversalHex(text)) {
  const name = path.join(out, `board-${boardId.toString(16)}.hex`);
  fs.writeFileSync(name, hex);
  console.log(`${boardId.toString(16)} ${name}`);
}
