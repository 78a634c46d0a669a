// Generated mazes' arguments: the maze in play's, and the URL that names it.

import { w } from './core.js';

// Argument `what` of the generated maze in play (0 seed, 1 size, 2 storeys, 3
// difficulty): the export's u32 arrives as a signed i32, so a seed from 2³¹ up
// would read negative.
export function mazeArg(what) {
  return w.level_maze(what) >>> 0;
}

// The URL says which maze is in play (`?seed=N&storeys=S`, size and
// difficulty when not the defaults), so it can be bookmarked or shared; for
// the other levels it has no query.
export function updateUrl() {
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
export function mazeFromUrl() {
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
