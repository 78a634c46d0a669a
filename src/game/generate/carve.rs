//! Carving a storey: the depth-first search that makes each storey a perfect
//! maze, the exit picked among its deep dead ends, the way through it marked,
//! and the extra marbles and the pits put in dead ends off that way. Apart from
//! the maze's cells ([`Maze`]) and its checks, because this is the part that
//! draws on the generator: every number here comes from the seed.

use rand_xorshift::XorShiftRng;

use super::{below, Maze, EAST, GOAL, HOLE, MAX_CELLS, MAX_SIZE_FOR_MARBLES, PATH, SOUTH, START};
use crate::game::level::MAX_MARBLES;

impl Maze {
    fn link(&mut self, storey: usize, c: usize, d: u8, to: usize) {
        let cells = &mut self.cells[storey];
        match d {
            0 => cells[to] |= EAST,
            1 => cells[c] |= EAST,
            2 => cells[to] |= SOUTH,
            _ => cells[c] |= SOUTH,
        }
    }

    /// A depth-first search from `entry` that opens a link to every unvisited cell
    /// it steps into (the recursive backtracker, with an explicit stack: a cell
    /// is pushed once, so the stack holds at most every cell). `depth` gets each
    /// cell's distance from `entry` along the tree (≤ 224: a `u8`).
    pub(super) fn carve(
        &mut self,
        storey: usize,
        entry: usize,
        depth: &mut [u8; MAX_CELLS],
        rng: &mut XorShiftRng,
    ) {
        const UNSEEN: u8 = u8::MAX;
        let n = self.len();
        depth[..n].fill(UNSEEN);
        let mut stack = [0u8; MAX_CELLS];
        let mut top = 1;
        stack[0] = entry as u8;
        depth[entry] = 0;
        while top > 0 {
            let c = usize::from(stack[top - 1]);
            let mut choices = [0u8; 4];
            let mut k = 0;
            for d in 0..4 {
                if let Some(m) = self.neighbour(c, d) {
                    if depth[m] == UNSEEN {
                        choices[k] = d;
                        k += 1;
                    }
                }
            }
            if k == 0 {
                top -= 1;
                continue;
            }
            let d = choices[below(rng, k as u32) as usize];
            if let Some(m) = self.neighbour(c, d) {
                self.link(storey, c, d, m);
                depth[m] = depth[c] + 1;
                stack[top] = m as u8;
                top += 1;
            }
        }
    }

    /// Open links of cell `c`.
    fn degree(&self, storey: usize, c: usize) -> u8 {
        (0..4).filter(|&d| self.open(storey, c, d)).count() as u8
    }

    /// A dead end other than `entry`, at random among those at least half as deep
    /// as the deepest (so the way through the storey is long, but not always the
    /// longest). A tree of two or more cells always has one.
    pub(super) fn pick_dead_end(
        &self,
        storey: usize,
        entry: usize,
        depth: &[u8; MAX_CELLS],
        rng: &mut XorShiftRng,
    ) -> usize {
        let n = self.len();
        let leaf = |c: usize| c != entry && self.degree(storey, c) == 1;
        let deepest = (0..n)
            .filter(|&c| leaf(c))
            .map(|c| depth[c])
            .max()
            .unwrap_or(0);
        let deep = |c: usize| leaf(c) && 2 * u16::from(depth[c]) >= u16::from(deepest);
        let count = (0..n).filter(|&c| deep(c)).count() as u32;
        let pick = below(rng, count.max(1)) as usize;
        (0..n).filter(|&c| deep(c)).nth(pick).unwrap_or(n - 1)
    }

    /// Marks the way from `exit` back to the storey's entry (down the depths), and
    /// counts its cells and turns.
    pub(super) fn mark_path(&mut self, storey: usize, exit: usize, depth: &[u8; MAX_CELLS]) {
        let mut c = exit;
        let mut last_dir = None;
        self.cells[storey][c] |= PATH;
        while depth[c] > 0 {
            let Some((d, m)) = (0..4u8)
                .filter(|&d| self.open(storey, c, d))
                .filter_map(|d| self.neighbour(c, d).map(|m| (d, m)))
                .find(|&(_, m)| depth[m] + 1 == depth[c])
            else {
                break;
            };
            if last_dir.is_some_and(|l| l != d) {
                self.turns += 1;
            }
            last_dir = Some(d);
            self.cells[storey][m] |= PATH;
            self.path_cells += 1;
            c = m;
        }
    }

    /// Dead ends of `storey` off the way through it, in cell order.
    fn spare_dead_ends(&self, storey: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.len()).filter(move |&c| {
            self.cells[storey][c] & (PATH | START | HOLE | GOAL) == 0 && self.degree(storey, c) == 1
        })
    }

    /// Sets `bit` on a dead end of `storey` off the way, chosen at random;
    /// nothing when there is none left.
    fn mark_spare_dead_end(&mut self, storey: usize, bit: u8, rng: &mut XorShiftRng) {
        let spare = self.spare_dead_ends(storey).count();
        if spare == 0 {
            return;
        }
        let pick = below(rng, spare as u32) as usize;
        let chosen = self.spare_dead_ends(storey).nth(pick);
        if let Some(c) = chosen {
            self.cells[storey][c] |= bit;
        }
    }

    /// From difficulty 4 a second marble, from 7 a third, each in a dead end of the
    /// top storey off the way (when there is one) — on mazes of up to
    /// [`MAX_SIZE_FOR_MARBLES`] cells a side.
    pub(super) fn add_marbles(&mut self, storey: usize, rng: &mut XorShiftRng) {
        if self.size > MAX_SIZE_FOR_MARBLES {
            return;
        }
        let extra = usize::from(self.difficulty >= 4) + usize::from(self.difficulty >= 7);
        for _ in 0..extra.min(MAX_MARBLES - 1) {
            self.mark_spare_dead_end(storey, START, rng);
        }
    }

    /// From difficulty 2, one pit per two levels of difficulty in dead ends of the
    /// lowest storey off the way to the goal (as many as there are).
    pub(super) fn add_pits(&mut self, rng: &mut XorShiftRng) {
        for _ in 0..self.difficulty / 2 {
            self.mark_spare_dead_end(0, HOLE, rng);
        }
    }
}
