//! The reachability check every maze passes before it is handed out
//! ([`Maze::every_start_reaches_the_goal`]): independent of how the maze was
//! carved, so that a bug in the carving is an error, never a maze the marble
//! cannot win.

use super::{Maze, GOAL, HOLE, MAX_SIZE, MAX_STOREYS, START};

impl Maze {
    /// The reachability check: from every start, a flood over the cells (until
    /// nothing new is reached; rows as bit masks, no queue) that moves along
    /// open links into cells with a floor, and from a hole above the lowest storey
    /// only down to the cell below, reaches the goal. Pits are never entered.
    pub fn every_start_reaches_the_goal(&self) -> bool {
        let n = usize::from(self.size);
        let storeys = usize::from(self.storeys);
        for s in 0..storeys {
            for c in 0..self.len() {
                if self.cells[s][c] & START == 0 {
                    continue;
                }
                let mut seen = [[0u16; MAX_SIZE as usize]; MAX_STOREYS];
                seen[s][c / n] |= 1 << (c % n);
                let mut grew = true;
                let mut won = false;
                while grew && !won {
                    grew = false;
                    for t in 0..storeys {
                        for a in 0..self.len() {
                            if seen[t][a / n] & (1 << (a % n)) == 0 {
                                continue;
                            }
                            let cell = self.cells[t][a];
                            won |= cell & GOAL != 0;
                            let mut reach = |t: usize, b: usize| {
                                if seen[t][b / n] & (1 << (b % n)) == 0 {
                                    seen[t][b / n] |= 1 << (b % n);
                                    grew = true;
                                }
                            };
                            if cell & HOLE != 0 {
                                // Over a hole: the marble drops (a pit is never entered).
                                if t > 0 {
                                    reach(t - 1, a);
                                }
                                continue;
                            }
                            for d in 0..4 {
                                if let Some(b) = self.neighbour(a, d) {
                                    let pit = t == 0 && self.cells[t][b] & HOLE != 0;
                                    if self.open(t, a, d) && !pit {
                                        reach(t, b);
                                    }
                                }
                            }
                        }
                    }
                }
                if !won {
                    return false;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;

    /// The check is not a formality: a maze whose way is cut fails it.
    #[test]
    fn the_check_catches_a_cut_way() {
        let mut m = generate(5, 6, 1, 0).unwrap();
        assert!(m.every_start_reaches_the_goal());
        for c in m.cells[0].iter_mut() {
            if *c & GOAL != 0 {
                // Wall the goal in.
                *c &= !(EAST | SOUTH);
            }
        }
        for c in 0..m.len() {
            for d in [1, 3] {
                if let Some(g) = m.neighbour(c, d) {
                    if m.cells[0][g] & GOAL != 0 {
                        m.cells[0][c] &= !(if d == 1 { EAST } else { SOUTH });
                    }
                }
            }
        }
        assert!(!m.every_start_reaches_the_goal());
        // Without the hole to the storey below, the top storey is a dead end.
        let mut m = generate(5, 4, 2, 0).unwrap();
        assert!(m.every_start_reaches_the_goal());
        for c in m.cells[1].iter_mut() {
            *c &= !HOLE;
        }
        assert!(!m.every_start_reaches_the_goal());
    }
}
