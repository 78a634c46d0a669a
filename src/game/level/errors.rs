//! What can be wrong with a level, where (line and column, in characters), and
//! how each is said: a short rule ([`LevelErrorKind::message`]) and the numbers
//! that broke it ([`LevelErrorKind::detail`], `Display`).

use super::scan::{count_chars, eq_bytes, without_bom};
use crate::physics::geometry::tiles::{LayoutError, MAX_PITCH_UM, MIN_PITCH_UM};
use crate::physics::world::SetupError;

/// What is wrong with a level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LevelErrorKind {
    /// A header line without `:`.
    MissingColon,
    /// A header key this format does not know.
    UnknownKey,
    /// A number that does not parse or has too many decimals.
    BadNumber,
    /// A number outside the key's range.
    OutOfRange {
        /// The key whose range it is.
        key: NumberKey,
    },
    /// An unknown name in `effects`, or `none` beside another effect.
    UnknownEffect,
    /// No `---` line.
    MissingSeparator,
    /// No grid rows after `---`.
    EmptyGrid,
    /// A row longer or shorter than the first.
    RaggedRow,
    /// More than 127 columns or rows.
    TooLarge,
    /// A character that is not `# . O S G`.
    BadTile,
    /// `S` or `G` on a short tile (even column or row).
    NotACell,
    /// No `S`, or more than [`MAX_MARBLES`](super::MAX_MARBLES).
    StartCount,
    /// No `G`, or more than `MAX_GOALS`.
    GoalCount,
    /// The cell pitch `s + l` is outside [`MIN_PITCH_UM`] ..= [`MAX_PITCH_UM`].
    PitchOutOfRange {
        /// `short_mm` in µm.
        short_um: u32,
        /// `long_mm` in µm.
        long_um: u32,
    },
    /// The marble does not fit in a cell (`2r ≥ l`).
    MarbleTooBig {
        /// `marble_radius_mm` in µm.
        radius_um: u32,
        /// `long_mm` in µm.
        long_um: u32,
    },
    /// The name is not valid UTF-8.
    BadName,
    /// More storeys than [`MAX_STOREYS`](crate::physics::geometry::grid::MAX_STOREYS).
    TooManyStoreys,
    /// A storey with more or fewer rows than the first.
    StoreyRows,
    /// A `===` with no rows before or after it.
    EmptyStorey,
    /// A wall under a hole of the storey above.
    HoleAboveWall,
    /// Bytes that are not UTF-8 ([`text`]).
    NotUtf8 {
        /// The first byte that is not (or does not start) a UTF-8 character.
        byte: u8,
    },
}

/// A header key whose value is a number: its name and its range, in one place
/// for the parser and its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NumberKey {
    /// `short_mm`.
    ShortMm,
    /// `long_mm`.
    LongMm,
    /// `marble_radius_mm`.
    MarbleRadiusMm,
    /// `restitution`.
    Restitution,
    /// `rolling_resistance`.
    RollingResistance,
    /// `time_limit_s`.
    TimeLimitS,
}

impl NumberKey {
    /// Every numeric key.
    pub const ALL: [NumberKey; 6] = [
        NumberKey::ShortMm,
        NumberKey::LongMm,
        NumberKey::MarbleRadiusMm,
        NumberKey::Restitution,
        NumberKey::RollingResistance,
        NumberKey::TimeLimitS,
    ];

    /// The key as written in a level.
    pub const fn name(self) -> &'static str {
        match self {
            NumberKey::ShortMm => "short_mm",
            NumberKey::LongMm => "long_mm",
            NumberKey::MarbleRadiusMm => "marble_radius_mm",
            NumberKey::Restitution => "restitution",
            NumberKey::RollingResistance => "rolling_resistance",
            NumberKey::TimeLimitS => "time_limit_s",
        }
    }

    /// Fraction digits the value may have; it is stored scaled by `10^decimals`.
    pub const fn decimals(self) -> u32 {
        match self {
            NumberKey::RollingResistance => 6,
            NumberKey::TimeLimitS => 0,
            _ => 3,
        }
    }

    /// The least and greatest value, scaled by `10^decimals`.
    pub const fn range(self) -> (u64, u64) {
        match self {
            NumberKey::ShortMm | NumberKey::LongMm | NumberKey::MarbleRadiusMm => (1, 100_000),
            NumberKey::Restitution => (0, 1000),
            NumberKey::RollingResistance => (0, 1_000_000),
            NumberKey::TimeLimitS => (1, 3600),
        }
    }

    /// The range in words, as the level format's table gives it.
    pub const fn range_text(self) -> &'static str {
        match self {
            NumberKey::ShortMm => "short_mm is 0.001 ..= 100",
            NumberKey::LongMm => "long_mm is 0.001 ..= 100",
            NumberKey::MarbleRadiusMm => "marble_radius_mm is 0.001 ..= 100",
            NumberKey::Restitution => "restitution is 0 ..= 1",
            NumberKey::RollingResistance => "rolling_resistance is 0 ..= 1",
            NumberKey::TimeLimitS => "time_limit_s is 1 ..= 3600",
        }
    }

    /// The key called `b[start..end]`.
    pub(super) const fn find(b: &[u8], start: usize, end: usize) -> Option<NumberKey> {
        let mut n = 0;
        while n < NumberKey::ALL.len() {
            if eq_bytes(b, start, end, NumberKey::ALL[n].name().as_bytes()) {
                return Some(NumberKey::ALL[n]);
            }
            n += 1;
        }
        None
    }
}

impl LevelErrorKind {
    /// A short description: the rule that was broken. (`Display` adds the numbers
    /// that broke it, for the kinds that have them.)
    pub const fn message(self) -> &'static str {
        match self {
            LevelErrorKind::MissingColon => "expected `key: value`",
            LevelErrorKind::UnknownKey => {
                "unknown header key (name, effects, short_mm, long_mm, marble_radius_mm, \
                 restitution, rolling_resistance, time_limit_s)"
            }
            LevelErrorKind::BadNumber => {
                "not a number (at most 3 decimals, rolling_resistance 6, time_limit_s none)"
            }
            LevelErrorKind::OutOfRange { .. } => "value out of range",
            LevelErrorKind::UnknownEffect => {
                "unknown effect (rolling, friction, board_motion; or none, alone)"
            }
            LevelErrorKind::MissingSeparator => "no `---` line between header and grid",
            LevelErrorKind::EmptyGrid => "the grid has no rows",
            LevelErrorKind::RaggedRow => "row length differs from the first row",
            LevelErrorKind::TooLarge => "grid larger than 127 tiles",
            LevelErrorKind::BadTile => "unknown tile (use # . O S G)",
            LevelErrorKind::NotACell => "S and G must be on a cell (odd column and odd row)",
            LevelErrorKind::StartCount => "need 1 to 4 marble starts (S)",
            LevelErrorKind::GoalCount => "need 1 to 4 goal cells (G)",
            LevelErrorKind::PitchOutOfRange { .. } => {
                "cell pitch short_mm + long_mm must be 1 ..= 100 mm"
            }
            LevelErrorKind::MarbleTooBig { .. } => {
                "marble does not fit a cell: 2 × marble_radius_mm must be less than long_mm"
            }
            LevelErrorKind::BadName => "name is not valid UTF-8",
            LevelErrorKind::TooManyStoreys => "more than 4 storeys",
            LevelErrorKind::StoreyRows => "storey has a different number of rows from the first",
            LevelErrorKind::EmptyStorey => "no rows between storey separators (===)",
            LevelErrorKind::HoleAboveWall => {
                "wall under a hole (O) of the storey above: a marble would sink onto its top"
            }
            LevelErrorKind::NotUtf8 { .. } => "not UTF-8",
        }
    }

    /// What [`Self::message`] leaves out that needs no numbers formatted: the
    /// range of a value out of range (`""` for the other kinds). A built-in
    /// level's build error, which cannot format numbers, adds it too.
    pub const fn detail(self) -> &'static str {
        match self {
            LevelErrorKind::OutOfRange { key } => key.range_text(),
            _ => "",
        }
    }
}

/// An error with the 1-based line and column it was found at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LevelError {
    /// 1-based line.
    pub line: u32,
    /// 1-based column (characters).
    pub column: u32,
    /// What is wrong.
    pub kind: LevelErrorKind,
}

/// Micrometres as millimetres, without trailing zeros (`100001` → `100.001`).
struct Mm(u32);

impl core::fmt::Display for Mm {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (whole, mut frac, mut digits) = (self.0 / 1000, self.0 % 1000, 3);
        if frac == 0 {
            return write!(f, "{whole}");
        }
        while frac % 10 == 0 {
            frac /= 10;
            digits -= 1;
        }
        write!(f, "{whole}.{frac:0digits$}")
    }
}

/// The rule, then the numbers that broke it.
impl core::fmt::Display for LevelErrorKind {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())?;
        match *self {
            LevelErrorKind::OutOfRange { key } => write!(f, ": {}", key.range_text()),
            LevelErrorKind::NotUtf8 { byte } => write!(f, " (byte 0x{byte:02X})"),
            LevelErrorKind::PitchOutOfRange { short_um, long_um } => write!(
                f,
                ", is {} + {} = {} mm",
                Mm(short_um),
                Mm(long_um),
                Mm(short_um.saturating_add(long_um))
            ),
            LevelErrorKind::MarbleTooBig { radius_um, long_um } => write!(
                f,
                ", is 2 × {} = {} mm against long_mm {} mm",
                Mm(radius_um),
                Mm(radius_um.saturating_mul(2)),
                Mm(long_um)
            ),
            _ => Ok(()),
        }
    }
}

impl core::fmt::Display for LevelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.column, self.kind)
    }
}

// The physics' setup errors in words (tools print these, never `{:?}`). They live
// here, next to the level format, because a level is what a person edits to fix them.
impl core::fmt::Display for LayoutError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LayoutError::ZeroWidth => f.write_str("short_mm and long_mm must not be zero"),
            LayoutError::PitchOutOfRange => write!(
                f,
                "cell pitch short_mm + long_mm is outside {} ..= {} mm",
                Mm(MIN_PITCH_UM),
                Mm(MAX_PITCH_UM)
            ),
        }
    }
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SetupError::Layout(e) => write!(f, "{e}"),
            SetupError::MarbleSize => f.write_str(
                "marble does not fit a cell: 2 × marble_radius_mm must be more than 0 and less \
                 than long_mm",
            ),
            SetupError::Parameter => {
                f.write_str("restitution above 1, or a step rate outside 64 ..= 16384 steps/s")
            }
            SetupError::MarbleCount => {
                f.write_str("no marble start, or more marbles than the world has room for")
            }
            SetupError::BadStart(n) => write!(
                f,
                "marble start {} (S number {} in reading order) overlaps a tile or lies \
                 outside the board",
                n + 1,
                n + 1
            ),
        }
    }
}

/// An error at `at` on the line that starts at `line_start`, its column counted
/// in characters.
pub(super) const fn err<T>(
    line: usize,
    b: &[u8],
    line_start: usize,
    at: usize,
    kind: LevelErrorKind,
) -> Result<T, LevelError> {
    Err(LevelError {
        line: line as u32,
        column: (count_chars(b, line_start, at) + 1) as u32,
        kind,
    })
}

/// Bytes read as a level's text (a file, the browser's buffer): the text, or a
/// [`LevelErrorKind::NotUtf8`] error at the first byte that is not UTF-8, with
/// its line and column counted as [`parse`](super::parse) counts them (characters, line 1 after
/// a byte-order mark).
pub fn text(bytes: &[u8]) -> Result<&str, LevelError> {
    let e = match core::str::from_utf8(bytes) {
        Ok(s) => return Ok(s),
        Err(e) => e,
    };
    let (valid, rest) = bytes.split_at(e.valid_up_to());
    let valid = without_bom(valid);
    let line_start = valid.iter().rposition(|&c| c == b'\n').map_or(0, |n| n + 1);
    Err(LevelError {
        line: (valid.iter().filter(|&&c| c == b'\n').count() + 1) as u32,
        column: (count_chars(valid, line_start, valid.len()) + 1) as u32,
        // `rest` is not empty: a prefix of UTF-8 would have been accepted.
        kind: LevelErrorKind::NotUtf8 {
            byte: rest.first().copied().unwrap_or_default(),
        },
    })
}
