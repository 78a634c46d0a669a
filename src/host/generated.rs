//! `--generate SEED`: the tools' options for a generated maze
//! ([`crate::game::generate`]), shared by `cargo sim` and `cargo play`.
//!
//! The maze's level text goes through the same run-time parser as a level file
//! (`super::parse_runtime`), so a generated level is played exactly as its
//! printed text (`cargo sim -- --generate 7 --print-level > my.level`) would be.

use std::format;
use std::string::{String, ToString};

use crate::game::generate::{generate, MAX_DIFFICULTY, MAX_SIZE, MIN_SIZE};
use crate::game::level::LevelView;

/// The options that choose a generated maze.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct GenerateArgs {
    /// Play a generated maze: the same seed always gives the same maze
    /// (0..=4294967295).
    // Negative numbers are let through as values so that `--generate -1` is
    // refused by the parser, which names the range, not taken for an option.
    #[arg(long, value_name = "SEED", conflicts_with = "level",
          allow_negative_numbers = true, value_parser = parse_seed)]
    pub(crate) generate: Option<u32>,
    /// Cells along a side of the generated maze [default: 6].
    // No `default_value_t`: clap does not check `requires` of an argument that
    // has a default, nor when `--level` (which conflicts with `--generate`) is
    // given: `level` reports `--size` without `--generate`.
    #[arg(long, value_name = "N", requires = "generate",
          value_parser = clap::value_parser!(u8).range(i64::from(MIN_SIZE)..=i64::from(MAX_SIZE)))]
    pub(crate) size: Option<u8>,
    /// Storeys of the generated maze (a hole drops the marble one storey) [default: 1].
    #[arg(long, value_name = "N", requires = "generate",
          value_parser = clap::value_parser!(u8).range(1..=4))]
    pub(crate) storeys: Option<u8>,
    /// Difficulty of the generated maze: friction from 1, pits from 2, more
    /// marbles from 4, board motion from 6 (on 1-2 storeys), tighter time limits
    /// [default: 2].
    #[arg(long, value_name = "D", requires = "generate",
          value_parser = clap::value_parser!(u8).range(0..=i64::from(MAX_DIFFICULTY)))]
    pub(crate) difficulty: Option<u8>,
}

/// A seed: any `u32`, written in decimal.
fn parse_seed(s: &str) -> Result<u32, String> {
    s.parse::<u32>()
        .map_err(|_| format!("{} is not in 0..={}", super::excerpt(s), u32::MAX))
}

/// `--size` when not given.
pub(crate) const DEFAULT_SIZE: u8 = 6;
/// `--difficulty` when not given.
pub(crate) const DEFAULT_DIFFICULTY: u8 = 2;

impl GenerateArgs {
    /// The generated maze's level text and the level parsed from it, when
    /// `--generate` was given.
    pub(crate) fn level(&self) -> Result<Option<(String, LevelView<'static>)>, String> {
        let Some(seed) = self.generate else {
            if self.size.is_some() || self.storeys.is_some() || self.difficulty.is_some() {
                return Err("--size, --storeys and --difficulty need --generate SEED".to_string());
            }
            return Ok(None);
        };
        let size = self.size.unwrap_or(DEFAULT_SIZE);
        let storeys = self.storeys.unwrap_or(1);
        let difficulty = self.difficulty.unwrap_or(DEFAULT_DIFFICULTY);
        let maze = generate(seed, size, storeys, difficulty)
            .map_err(|e| format!("--generate {seed}: {e}"))?;
        let text = maze.to_string();
        let view = super::parse_runtime(text.clone())
            .map_err(|e| format!("internal error: generated maze {seed} does not parse: {e}"))?;
        Ok(Some((text, view)))
    }
}
