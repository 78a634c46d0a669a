//! Host tools (`tools` feature, std): the simulator CLI ([`sim`], `cargo sim`) and
//! the terminal player ([`play`], `cargo play`, and [`race`], `cargo play --
//! --race`). The `sim` and `play` binaries are thin wrappers around
//! [`sim::main`], [`play::main`] and [`race::main`], so the logic lives in the
//! library where it is documented and type-checked with the rest of the crate.
//! What `cargo sim --gif` records of a game, the matrix picture and (for a level
//! with storeys) every storey's map beside it, is composed in [`storey_maps`] and
//! written by [`gif_out`].
//!
//! Nothing in here is used by the firmware: the module (and its dependencies clap,
//! gif and crossterm) exists only when the `tools` feature is on.

pub(crate) mod generated;
pub mod ghost_file;
pub mod gif_out;
pub mod play;
pub mod race;
pub mod motion_trace;
pub mod report;
pub mod sim;
pub mod storey_maps;
pub(crate) mod tilt_trace;

use std::boxed::Box;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use crate::game::level::{parse, text, LevelView};
use crate::game::levels::{by_name, LEVELS};
use crate::physics::geometry::grid::{words_for, MAX_LAYERS, MAX_TILES_XZ};

/// Occupancy words of the largest level the format allows (127 × 127 tiles on 4
/// storeys, 16 KiB):
/// every level read at run time is parsed into a grid of this size.
pub(crate) const MAX_WORDS: usize = words_for(MAX_TILES_XZ, MAX_LAYERS, MAX_TILES_XZ);

/// A level chosen on the command line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Loaded {
    /// The level.
    pub(crate) view: LevelView<'static>,
    /// Its index in [`LEVELS`] when it is a built-in one.
    pub(crate) builtin: Option<usize>,
}

/// Names of the built-in levels, comma separated (for messages).
pub(crate) fn builtin_names() -> String {
    LEVELS
        .iter()
        .map(|l| l.info.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Parses a level source read at run time. The source and the parsed level are
/// leaked: a tool loads a handful of levels per process. The error is
/// `line:column: message`.
pub(crate) fn parse_runtime(
    src: String,
) -> Result<LevelView<'static>, crate::game::level::LevelError> {
    let src: &'static str = Box::leak(src.into_boxed_str());
    let level = parse::<MAX_WORDS>(src)?;
    let level: &'static _ = Box::leak(Box::new(level));
    Ok(level.view())
}

/// A built-in level by name, or else a level file. The error names the file with
/// `FILE:line:column: message` for a malformed level (bytes that are not UTF-8
/// included).
pub(crate) fn load_level(arg: &str) -> Result<Loaded, String> {
    if let Some((i, view)) = by_name(arg) {
        return Ok(Loaded {
            view,
            builtin: Some(i),
        });
    }
    let bytes = match std::fs::read(arg) {
        Ok(b) => b,
        Err(e) => {
            return Err(format!(
                "level {} is neither a built-in level ({}) nor a readable file: {e}",
                excerpt(arg),
                builtin_names()
            ))
        }
    };
    let src = text(&bytes).map_err(|e| format!("{arg}:{e}"))?.to_string();
    let view = parse_runtime(src).map_err(|e| format!("{arg}:{e}"))?;
    Ok(Loaded {
        view,
        builtin: None,
    })
}

/// Characters of offending text an error line quotes at most ([`excerpt`]).
pub(crate) const EXCERPT_CHARS: usize = 60;

/// `text` quoted for an error line: in backticks, and when longer than
/// `EXCERPT_CHARS` characters its first ones and an ellipsis (a 100 000-digit
/// number is reported in a line, not echoed whole).
pub(crate) fn excerpt(text: &str) -> String {
    match text.char_indices().nth(EXCERPT_CHARS) {
        Some((cut, _)) => format!("`{}…`", &text[..cut]),
        None => format!("`{text}`"),
    }
}

/// A message from clap with every `'…'` it quotes cut as [`excerpt`] cuts (clap
/// echoes an argument it refuses whole). Quotes are paired in order; a line
/// still longer than [`EXCERPT_CHARS`] · 3 characters (an argument with a quote
/// in it) is cut there.
pub(crate) fn shorten_quotes(message: &str) -> String {
    let mut out = String::with_capacity(message.len().min(4096));
    for (n, line) in message.split('\n').enumerate() {
        if n > 0 {
            out.push('\n');
        }
        let mut short = String::new();
        for (k, part) in line.split('\'').enumerate() {
            if k > 0 {
                short.push('\'');
            }
            // Odd parts lie between a pair of quotes.
            match part.char_indices().nth(EXCERPT_CHARS) {
                Some((cut, _)) if k % 2 == 1 => {
                    short.push_str(&part[..cut]);
                    short.push('…');
                }
                _ => short.push_str(part),
            }
        }
        match short.char_indices().nth(3 * EXCERPT_CHARS) {
            Some((cut, _)) => {
                out.push_str(&short[..cut]);
                out.push('…');
            }
            None => out.push_str(&short),
        }
    }
    out
}

/// A scalar type the physics can run on, chosen by name at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Backend {
    /// `fixed::types::I8F24`, the firmware's default (`i8f24`).
    I8F24,
    /// `fixed::types::I16F16` (`i16f16`).
    I16F16,
    /// `fixed::types::I32F32` (`i32f32`).
    I32F32,
    /// `f32`.
    F32,
    /// `f32` with micromath's square root (`f32-micromath`).
    MicroF32,
    /// `f64`.
    F64,
}

impl Backend {
    /// Every backend, the default first.
    pub(crate) const ALL: [Backend; 6] = [
        Backend::I8F24,
        Backend::I16F16,
        Backend::I32F32,
        Backend::F32,
        Backend::MicroF32,
        Backend::F64,
    ];

    /// The name used on the command line and in reports (`Scalar::NAME`).
    pub(crate) fn name(self) -> &'static str {
        use crate::physics::Scalar;
        match self {
            Backend::I8F24 => fixed::types::I8F24::NAME,
            Backend::I16F16 => fixed::types::I16F16::NAME,
            Backend::I32F32 => fixed::types::I32F32::NAME,
            Backend::F32 => f32::NAME,
            Backend::MicroF32 => crate::physics::MicroF32::NAME,
            Backend::F64 => f64::NAME,
        }
    }

    /// The backend called `name`, or a message listing the known ones.
    pub(crate) fn from_name(name: &str) -> Result<Backend, String> {
        Backend::ALL
            .iter()
            .copied()
            .find(|b| b.name() == name)
            .ok_or_else(|| {
                format!(
                    "unknown backend {} (known: {})",
                    excerpt(name),
                    Backend::ALL
                        .iter()
                        .map(|b| b.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
    }

    /// Runs `job` with this backend's scalar type.
    pub(crate) fn run<J: WithScalar>(self, job: J) -> J::Output {
        match self {
            Backend::I8F24 => job.run::<fixed::types::I8F24>(),
            Backend::I16F16 => job.run::<fixed::types::I16F16>(),
            Backend::I32F32 => job.run::<fixed::types::I32F32>(),
            Backend::F32 => job.run::<f32>(),
            Backend::MicroF32 => job.run::<crate::physics::MicroF32>(),
            Backend::F64 => job.run::<f64>(),
        }
    }
}

impl core::fmt::Display for Backend {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Work that is generic over the scalar type ([`Backend::run`] picks it).
pub(crate) trait WithScalar {
    /// What the work returns.
    type Output;
    /// Does the work with scalar `S`.
    fn run<S: crate::physics::Scalar>(self) -> Self::Output;
}

/// Drops one leading `--` from the arguments: the cargo aliases end in `--`, so
/// `cargo sim -- --level x` hands the binary `-- --level x`.
pub(crate) fn args_without_separator() -> Vec<std::ffi::OsString> {
    let mut args: Vec<_> = std::env::args_os().collect();
    if args.get(1).is_some_and(|a| a == "--") {
        args.remove(1);
    }
    args
}

/// The process arguments (without the aliases' `--`) parsed into `A`; on failure,
/// clap's message is printed and the exit status returned (2 for an error, 0 for
/// `--help` and `--version`). An error quotes at most `EXCERPT_CHARS` of an
/// argument (`shorten_quotes`).
pub fn parse_args<A: clap::Parser>() -> Result<A, i32> {
    A::try_parse_from(args_without_separator()).map_err(|e| {
        if e.use_stderr() {
            std::eprint!("{}", shorten_quotes(&e.render().to_string()));
            2
        } else {
            let _ = e.print();
            0
        }
    })
}

/// `s` as a JSON string literal.
pub(crate) fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A finite `f64` as a JSON number (`null` otherwise).
pub(crate) fn json_number(x: f64) -> String {
    if x.is_finite() {
        x.to_string()
    } else {
        "null".to_string()
    }
}

/// The whole level as an image, one pixel per tile (`nx`×`nz`, row-major
/// brightness 0..=15), drawn by [`crate::render`] exactly as the LED matrix shows it
/// (goal blinking with the game's frame counter, marbles anti-aliased).
pub fn level_picture<S: crate::physics::Scalar>(
    game: &crate::game::rules::Game<'_, S>,
) -> (usize, usize, Vec<u8>) {
    let info = &game.level().info;
    // The smallest square matrix that holds the level (a level has ≤ 127 tiles a side).
    match info.nx.max(info.nz) {
        0..=16 => picture::<S, 16>(game),
        17..=32 => picture::<S, 32>(game),
        33..=64 => picture::<S, 64>(game),
        _ => picture::<S, 128>(game),
    }
}

fn picture<S: crate::physics::Scalar, const N: usize>(
    game: &crate::game::rules::Game<'_, S>,
) -> (usize, usize, Vec<u8>) {
    use crate::render::{blink_on, render_world, Viewport};
    let level = game.level();
    let (w, h) = (
        (level.info.nx as usize).min(N),
        (level.info.nz as usize).min(N),
    );
    let blink = blink_on(game.frames(), game.config().frame_log2);
    let frame: crate::matrix::Frame<N, N> =
        render_world(level, game.world(), blink, Viewport::new(0, 0));
    let mut px = Vec::with_capacity(w * h);
    for row in frame.rows().iter().take(h) {
        px.extend_from_slice(&row[..w]);
    }
    (w, h, px)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excerpts_cut_at_60_characters() {
        assert_eq!(excerpt("q15"), "`q15`");
        let sixty = "é".repeat(EXCERPT_CHARS);
        assert_eq!(excerpt(&sixty), format!("`{sixty}`"));
        assert_eq!(excerpt(&format!("{sixty}x")), format!("`{sixty}…`"));
    }

    #[test]
    fn clap_quotes_are_shortened() {
        let long = "x".repeat(1000);
        let cut = format!("{}…", "x".repeat(EXCERPT_CHARS));
        assert_eq!(
            shorten_quotes(&format!(
                "error: unexpected argument '{long}' found\n\n  tip: '-- {long}'\n"
            )),
            format!(
                "error: unexpected argument '{cut}' found\n\n  tip: '-- {}…'\n",
                "x".repeat(EXCERPT_CHARS - 3)
            )
        );
        // A quote inside the argument pairs the rest wrongly: the line is cut.
        let odd = shorten_quotes(&format!(
            "error: invalid value 'it's {long}' for '--backend'"
        ));
        assert!(odd.chars().count() <= 3 * EXCERPT_CHARS + 1, "{odd}");
        assert!(odd.ends_with('…'));
        assert_eq!(shorten_quotes("short 'ok'\n"), "short 'ok'\n");
    }
}
