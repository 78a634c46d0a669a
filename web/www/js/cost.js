// What a game frame costs the module, for the HUD: the mean of a window of
// the last frames' times.

// Frames whose mean cost the HUD shows.
const COST_WINDOW = 256;

const costs = new Float64Array(COST_WINDOW);
let costCount = 0;

// Keeps one frame's cost, ms.
export function recordCost(ms) {
  costs[costCount++ % COST_WINDOW] = ms;
}

// The mean cost of the last frames (up to COST_WINDOW), ms; null before the first.
export function meanCost() {
  const n = Math.min(costCount, COST_WINDOW);
  if (n === 0) return null;
  let sum = 0;
  for (let i = 0; i < n; i++) sum += costs[i];
  return sum / n;
}
