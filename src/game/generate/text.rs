//! The level text of a maze ([`Maze::write_text`], `Display`): the same
//! format as the built-in levels ([`crate::game::level`]), written without
//! `core::fmt`'s number formatting so that the micro:bit v1 can afford it.

use core::fmt;

use super::{Maze, EAST, GOAL, HOLE, SOUTH, START};

impl Maze {
    /// The tile character at column `i`, row `k` of `storey`.
    fn tile(&self, storey: usize, i: usize, k: usize) -> char {
        let n = usize::from(self.size);
        let last = 2 * n;
        if i == 0
            || k == 0
            || i == last
            || k == last
            || (i.is_multiple_of(2) && k.is_multiple_of(2))
        {
            return '#';
        }
        let cell = |x: usize, z: usize| self.cells[storey][z * n + x];
        match (i % 2, k % 2) {
            (1, 1) => {
                let c = cell(i / 2, k / 2);
                if c & START != 0 {
                    'S'
                } else if c & GOAL != 0 {
                    'G'
                } else if c & HOLE != 0 {
                    'O'
                } else {
                    '.'
                }
            }
            // A short tile between two cells along x' (even column) or z'.
            (0, _) if cell(i / 2 - 1, k / 2) & EAST != 0 => '.',
            (_, 0) if cell(i / 2, k / 2 - 1) & SOUTH != 0 => '.',
            _ => '#',
        }
    }
}

/// The level text (see [`crate::game::level`]): `Maze::write_text`.
impl fmt::Display for Maze {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_text(f)
    }
}

impl Maze {
    /// Writes the level text (see [`crate::game::level`]): a header naming the
    /// maze by its arguments, then the storeys top to bottom. Strings and
    /// digits only, no format machinery: a board writes its mazes with this,
    /// and `core::fmt`'s number formatting is kilobytes of flash the micro:bit
    /// v1 does not have to spare.
    pub(crate) fn write_text<W: fmt::Write>(&self, w: &mut W) -> fmt::Result {
        w.write_str("name: ")?;
        write_name(w, self.seed, self.size, self.storeys, self.difficulty)?;
        w.write_str("\neffects: rolling")?;
        if self.difficulty >= 1 {
            w.write_str(", friction")?;
        }
        if self.board_motion() {
            w.write_str(", board_motion")?;
        }
        w.write_str("\ntime_limit_s: ")?;
        decimal(w, self.time_limit_s().into())?;
        w.write_str("\n---\n")?;
        let tiles = 2 * usize::from(self.size) + 1;
        for storey in (0..usize::from(self.storeys)).rev() {
            for k in 0..tiles {
                for i in 0..tiles {
                    w.write_char(self.tile(storey, i, k))?;
                }
                w.write_char('\n')?;
            }
            if storey > 0 {
                w.write_str("===\n")?;
            }
        }
        Ok(())
    }
}

/// A generated maze's name, `maze-SEED-NxNxS-dD` (seed, cells a side twice,
/// storeys, difficulty): its level text's `name:`, which the boards log and the
/// demos' checks look for. Digits without `core::fmt`, as [`Maze::write_text`].
pub(crate) fn write_name<W: fmt::Write>(
    w: &mut W,
    seed: u32,
    size: u8,
    storeys: u8,
    difficulty: u8,
) -> fmt::Result {
    w.write_str("maze-")?;
    decimal(w, seed)?;
    w.write_char('-')?;
    decimal(w, size.into())?;
    w.write_char('x')?;
    decimal(w, size.into())?;
    w.write_char('x')?;
    decimal(w, storeys.into())?;
    w.write_str("-d")?;
    decimal(w, difficulty.into())
}

/// `n` in decimal, without leading zeros: from the largest power of ten not
/// above it (no digit buffer to index, so no bounds check to panic).
fn decimal<W: fmt::Write>(w: &mut W, n: u32) -> fmt::Result {
    let mut power = 1u32;
    // `power · 10 ≤ n` here, so it cannot overflow.
    while n / power >= 10 {
        power *= 10;
    }
    loop {
        w.write_char(char::from(b'0' + (n / power % 10) as u8))?;
        if power == 1 {
            return Ok(());
        }
        power /= 10;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_written_as_format_writes_them() {
        extern crate std;
        use std::string::{String, ToString};
        for n in [0, 1, 9, 10, 99, 100, 4_096, 1_000_000_000, u32::MAX] {
            let mut s = String::new();
            decimal(&mut s, n).unwrap();
            assert_eq!(s, n.to_string());
        }
    }
}
