//! The text level format, parsed by one `const fn` at compile time (built-in levels
//! live in flash, and a malformed one fails the build naming its line and column)
//! and at run time (host tools get the same error as a value — never a panic).
//!
//! ```text
//! name: Corridor            ← header: `key: value` lines, all optional
//! effects: rolling, friction
//! ---                       ← end of header
//! #########                 ← grid: one character per tile column [i, *, k]
//! #S.....G#
//! #########
//! ```
//!
//! | key | meaning | default |
//! |-----|---------|---------|
//! | `name` | shown by tools | `untitled` |
//! | `short_mm` | short tile width `s` (walls, posts), 0.001 ..= 100 | `2` |
//! | `long_mm` | long tile width `l` (cells), 0.001 ..= 100; pitch `s + l` 1 ..= 100 | `10` |
//! | `marble_radius_mm` | marble radius, 0.001 ..= 100 and `2r < l` | `3.5` |
//! | `restitution` | `e` in eq. 1, 0 ..= 1 | `0.5` |
//! | `effects` | the effects that are on: a comma list of `rolling`, `friction`, `board_motion`; empty or `none` for none | `rolling` |
//! | `rolling_resistance` | rolling-resistance coefficient (with `friction`) | `0.01` |
//! | `time_limit_s` | seconds before the attempt times out, 1 ..= 3600 | `60` |
//!
//! `effects` is the exact list of what is on: `effects: friction` slides with
//! friction (no rolling), `effects:` alone or `effects: none` is a marble that
//! slides without friction (it accelerates at `g·sinθ`, not the rolling `5/7` of
//! it); without the key a level rolls. A later `effects` line replaces an earlier one.
//!
//! Numbers take up to three decimals (`rolling_resistance` six). Grid characters:
//! `#` wall (a tile in layer `j = 1` on top of the floor), `.` floor, `O` hole (no
//! floor tile), `S` marble start, `G` goal. Column `i` is the character's position,
//! row `k` the line's; even indices are short tiles, odd ones long, so `S` and `G`
//! must sit at odd column and odd row (a long×long cell). Holes and several `S` switch
//! on the `holes` and `marbles` effects. All rows have the same length, at most 127.
//!
//! # Storeys
//!
//! A maze of several storeys (eq. 5 along y': storey `n` is the floor slab
//! `j = 2n` and the wall layer `j = 2n + 1` on it, one pitch above storey
//! `n − 1`) lists them **top to bottom**, each a grid as above, separated by a
//! line `===`. Every storey has the first one's rows and columns. A storey's
//! floor is the ceiling of the storey below; the top storey has the lid. `O` is a
//! hole into the storey below (in the lowest storey: out of the maze), so it may
//! not lie over a wall of the storey below (the marble would sink onto the
//! wall's top, 2 mm down, and stick there). `S` and `G` may be on any storey; a
//! maze of several storeys always moves in 3-D (the `holes` effect).
//!
//! ```text
//! ---
//! #######                   ← top storey (here storey 1)
//! #S.O..#
//! #######
//! ===
//! #######                   ← the storey below (storey 0)
//! #...G.#
//! #######
//! ```
//!
//! The parser refuses what the physics setup ([`Params::new`]) would refuse of a
//! header (pitch `s + l` 1 ..= 100 mm, `2r < l`), at the value that breaks the rule
//! (the later of the keys involved). A leading UTF-8 byte-order mark is skipped
//! (columns on line 1 count from the first character after it).
//!
//! Text read as bytes (a file, the browser's buffer) goes through [`text`] first:
//! bytes that are not UTF-8 are an error at their line and column
//! ([`LevelErrorKind::NotUtf8`]), like any other.
//!
//! [`Params::new`]: crate::physics::world::Params::new

use crate::physics::dynamics::effects::Effects;
use crate::physics::geometry::grid::{words_for, TileGrid, Tiles, MAX_STOREYS, MAX_TILES_XZ};
use crate::physics::geometry::tiles::LayoutError;
pub use crate::physics::geometry::tiles::{MAX_PITCH_UM, MIN_PITCH_UM};
use crate::physics::world::{PhysicsSpec, SetupError};

/// Most marbles a level may start (several `S`).
pub const MAX_MARBLES: usize = 4;
/// Most goal cells a level may have.
pub const MAX_GOALS: usize = 4;

/// The line between two storeys of the grid (listed top to bottom).
const STOREY_SEPARATOR: &[u8] = b"===";

/// A long×long cell on a storey (odd `i`, odd `k`; storey 0 is the lowest):
/// where a marble starts or a goal lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cell {
    /// Column along x'.
    pub i: u8,
    /// Row along z'.
    pub k: u8,
    /// Storey (its floor slab is layer `j = 2·storey`).
    pub storey: u8,
}

impl Cell {
    /// Cell `(i, k)` on storey `storey`.
    pub const fn new(i: u8, k: u8, storey: u8) -> Self {
        Cell { i, k, storey }
    }
}

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
    /// No `S`, or more than [`MAX_MARBLES`].
    StartCount,
    /// No `G`, or more than [`MAX_GOALS`].
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
    /// More storeys than [`MAX_STOREYS`].
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
    const fn find(b: &[u8], start: usize, end: usize) -> Option<NumberKey> {
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

/// Everything about a level except its tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelInfo<'a> {
    /// The level's name.
    pub name: &'a str,
    /// Physics parameters and effects.
    pub spec: PhysicsSpec,
    /// Seconds before the attempt times out.
    pub time_limit_s: u16,
    /// Tiles along x' (columns).
    pub nx: u8,
    /// Tiles along z' (rows).
    pub nz: u8,
    /// Storeys (1 ..= [`MAX_STOREYS`]).
    pub storeys: u8,
    starts: [Cell; MAX_MARBLES],
    n_starts: u8,
    goals: [Cell; MAX_GOALS],
    n_goals: u8,
}

impl LevelInfo<'_> {
    /// Start cells, in reading order (top storey first).
    pub fn starts(&self) -> &[Cell] {
        &self.starts[..self.n_starts as usize]
    }
    /// Goal cells, in reading order (top storey first).
    pub fn goals(&self) -> &[Cell] {
        &self.goals[..self.n_goals as usize]
    }
}

/// A parsed level: header and owned tiles (`WORDS` words of occupancy bits).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level<'a, const WORDS: usize> {
    /// The header and the cells that matter to the rules.
    pub info: LevelInfo<'a>,
    /// `tile_state`.
    pub grid: TileGrid<WORDS>,
}

/// A borrowed level: what the game, the renderer and the autopilot take.
#[derive(Clone, Copy, Debug)]
pub struct LevelView<'a> {
    /// Header and cells.
    pub info: LevelInfo<'a>,
    /// Tiles.
    pub tiles: Tiles<'a>,
}

impl<'a, const WORDS: usize> Level<'a, WORDS> {
    /// The borrowed view.
    pub const fn view(&'a self) -> LevelView<'a> {
        LevelView {
            info: self.info,
            tiles: self.grid.view(),
        }
    }
}

/// Occupancy words a level needs (`0` when its grid is malformed; `parse` then reports
/// why). Use it to size [`Level`] for a `const` level.
pub const fn words_needed(src: &str) -> usize {
    let b = without_bom(src.as_bytes());
    let Some(grid_start) = grid_start(b) else {
        return 1;
    };
    let (nx, nz, storeys) = grid_shape(b, grid_start);
    let storeys = if storeys == 0 {
        1
    } else if storeys > MAX_STOREYS {
        MAX_STOREYS
    } else {
        storeys
    };
    let w = words_for(
        if nx == 0 { 1 } else { nx },
        2 * storeys,
        if nz == 0 { 1 } else { nz },
    );
    if w == 0 {
        1
    } else {
        w
    }
}

/// The text after a leading UTF-8 byte-order mark (`EF BB BF`), if there is one:
/// editors on some systems save one, and it is not part of the first line.
const fn without_bom(b: &[u8]) -> &[u8] {
    if b.len() >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF {
        b.split_at(3).1
    } else {
        b
    }
}

/// Bytes read as a level's text (a file, the browser's buffer): the text, or a
/// [`LevelErrorKind::NotUtf8`] error at the first byte that is not UTF-8, with
/// its line and column counted as [`parse`] counts them (characters, line 1 after
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

/// Where a header value was given: (line, line start, value start); line 0 if not.
type At = (usize, usize, usize);

/// The later of two header values (the one that completed a broken rule).
const fn later(a: At, b: At) -> At {
    if a.0 >= b.0 {
        a
    } else {
        b
    }
}

const fn line_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i] != b'\n' {
        i += 1;
    }
    i
}

/// The end of a line without a trailing `\r` and spaces.
const fn trim_end(b: &[u8], start: usize, mut end: usize) -> usize {
    while end > start && (b[end - 1] == b'\r' || b[end - 1] == b' ' || b[end - 1] == b'\t') {
        end -= 1;
    }
    end
}

const fn skip_spaces(b: &[u8], mut i: usize, end: usize) -> usize {
    while i < end && (b[i] == b' ' || b[i] == b'\t') {
        i += 1;
    }
    i
}

/// Byte offset of the first grid row (after the `---` line).
const fn grid_start(b: &[u8]) -> Option<usize> {
    let mut i = 0;
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        if t - i == 3 && b[i] == b'-' && b[i + 1] == b'-' && b[i + 2] == b'-' {
            return Some(if e < b.len() { e + 1 } else { e });
        }
        i = e + 1;
    }
    None
}

/// Whether the line `[start, end)` (trimmed) separates two storeys.
const fn is_separator(b: &[u8], start: usize, end: usize) -> bool {
    eq_bytes(b, start, end, STOREY_SEPARATOR)
}

/// Columns of the first row, rows of the first storey, and storeys (rows
/// before the first `===`, and one more storey per `===`).
const fn grid_shape(b: &[u8], start: usize) -> (usize, usize, usize) {
    let mut i = start;
    let mut nx = 0;
    let mut nz = 0;
    let mut storeys = 0;
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        if t > i {
            if is_separator(b, i, t) {
                storeys += 1;
            } else {
                if nx == 0 && nz == 0 {
                    nx = count_chars(b, i, t);
                }
                if storeys == 0 {
                    nz += 1;
                }
            }
        }
        i = e + 1;
    }
    (nx, nz, storeys + 1)
}

const fn count_chars(b: &[u8], start: usize, end: usize) -> usize {
    let mut n = 0;
    let mut i = start;
    while i < end {
        if b[i] & 0xC0 != 0x80 {
            n += 1;
        }
        i += 1;
    }
    n
}

const fn err<T>(
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

const fn eq_bytes(b: &[u8], start: usize, end: usize, word: &[u8]) -> bool {
    if end - start != word.len() {
        return false;
    }
    let mut i = 0;
    while i < word.len() {
        if b[start + i] != word[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// A well-formed header number: its value, or too many digits to hold (which is
/// out of any key's range, not "not a number").
enum Digits {
    /// The value scaled by `10^decimals`.
    Value(u64),
    /// More than 10^12 before scaling.
    Huge,
}

/// A decimal with at most `decimals` fraction digits, scaled by `10^decimals`.
const fn decimal(b: &[u8], start: usize, end: usize, decimals: u32) -> Option<Digits> {
    let mut i = start;
    let mut value: u64 = 0;
    let mut huge = false;
    let mut seen_digit = false;
    let mut frac: i32 = -1;
    while i < end {
        let c = b[i];
        if c == b'.' {
            if frac >= 0 {
                return None;
            }
            frac = 0;
        } else if c.is_ascii_digit() {
            if frac >= 0 {
                if frac as u32 >= decimals {
                    return None;
                }
                frac += 1;
            }
            if !huge {
                // At most 10^12 · 10 + 9: no overflow.
                value = value * 10 + (c - b'0') as u64;
                huge = value > 1_000_000_000_000;
            }
            seen_digit = true;
        } else {
            return None;
        }
        i += 1;
    }
    if !seen_digit {
        return None;
    }
    if huge {
        return Some(Digits::Huge);
    }
    let used = if frac < 0 { 0 } else { frac as u32 };
    let mut scale = used;
    while scale < decimals {
        value *= 10;
        scale += 1;
    }
    Some(Digits::Value(value))
}

/// Parses a level. `WORDS` must be at least [`words_needed`]`(src)`.
pub const fn parse<const WORDS: usize>(src: &str) -> Result<Level<'_, WORDS>, LevelError> {
    let b = without_bom(src.as_bytes());
    if grid_start(b).is_none() {
        // Without `---` every grid row would read as a bad header line: say what is missing.
        let mut lines = 1;
        let mut p = 0;
        while p < b.len() {
            if b[p] == b'\n' && p + 1 < b.len() {
                lines += 1;
            }
            p += 1;
        }
        return Err(LevelError {
            line: lines + 1,
            column: 1,
            kind: LevelErrorKind::MissingSeparator,
        });
    }
    let mut spec = PhysicsSpec::DEFAULT;
    let mut effects = Effects {
        rolling: true,
        ..Effects::NONE
    };
    let mut name: &str = "untitled";
    let mut time_limit_s = 60u16;
    let mut short_at: At = (0, 0, 0);
    let mut long_at: At = (0, 0, 0);
    let mut radius_at: At = (0, 0, 0);
    let mut i = 0;
    let mut line = 1;
    let mut separator = false;
    // Header.
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        let s = skip_spaces(b, i, t);
        if eq_bytes(b, s, t, b"---") {
            separator = true;
            i = if e < b.len() { e + 1 } else { e };
            line += 1;
            break;
        }
        if s < t {
            let mut colon = s;
            while colon < t && b[colon] != b':' {
                colon += 1;
            }
            if colon == t {
                return err(line, b, i, s, LevelErrorKind::MissingColon);
            }
            let kend = trim_end(b, s, colon);
            let v = skip_spaces(b, colon + 1, t);
            if eq_bytes(b, s, kend, b"name") {
                let (_, rest) = b.split_at(v);
                let (bytes, _) = rest.split_at(t - v);
                match core::str::from_utf8(bytes) {
                    Ok(n) => name = n,
                    Err(_) => return err(line, b, i, v, LevelErrorKind::BadName),
                }
            } else if eq_bytes(b, s, kend, b"effects") {
                // The exact list of what is on (holes and marbles follow from the grid).
                effects = Effects::NONE;
                let mut none_at = 0;
                let mut named = 0;
                let mut p = v;
                while p < t {
                    let p0 = skip_spaces(b, p, t);
                    let mut q = p0;
                    while q < t && b[q] != b',' {
                        q += 1;
                    }
                    let qe = trim_end(b, p0, q);
                    if eq_bytes(b, p0, qe, b"rolling") {
                        effects.rolling = true;
                    } else if eq_bytes(b, p0, qe, b"friction") {
                        effects.friction = true;
                    } else if eq_bytes(b, p0, qe, b"board_motion") {
                        effects.board_motion = true;
                    } else if eq_bytes(b, p0, qe, b"none") {
                        none_at = p0;
                    } else if qe > p0 {
                        return err(line, b, i, p0, LevelErrorKind::UnknownEffect);
                    }
                    if qe > p0 {
                        named += 1;
                    }
                    // `none` beside an effect says two things: neither is taken.
                    if none_at > 0 && named > 1 {
                        return err(line, b, i, none_at, LevelErrorKind::UnknownEffect);
                    }
                    p = q + 1;
                }
            } else {
                let Some(key) = NumberKey::find(b, s, kend) else {
                    return err(line, b, i, s, LevelErrorKind::UnknownKey);
                };
                let Some(n) = decimal(b, v, t, key.decimals()) else {
                    return err(line, b, i, v, LevelErrorKind::BadNumber);
                };
                let (lo, hi) = key.range();
                // Past `decimal`'s bound the number is still a number: out of range.
                let n = match n {
                    Digits::Value(n) if n >= lo && n <= hi => n as u32,
                    _ => return err(line, b, i, v, LevelErrorKind::OutOfRange { key }),
                };
                match key {
                    NumberKey::ShortMm => {
                        spec.short_um = n;
                        short_at = (line, i, v);
                    }
                    NumberKey::LongMm => {
                        spec.long_um = n;
                        long_at = (line, i, v);
                    }
                    NumberKey::MarbleRadiusMm => {
                        spec.radius_um = n;
                        radius_at = (line, i, v);
                    }
                    NumberKey::Restitution => spec.restitution_milli = n,
                    NumberKey::RollingResistance => spec.rolling_resistance_ppm = n,
                    // 1 ..= 3600, checked above.
                    NumberKey::TimeLimitS => time_limit_s = n as u16,
                }
            }
        }
        i = e + 1;
        line += 1;
    }
    if !separator {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::MissingSeparator,
        });
    }
    // What `Params::new` checks, in its order (each value is already 0.001 ..= 100 mm,
    // so no width is zero). A rule of two values is reported at the later one given.
    let pitch = spec.short_um as u64 + spec.long_um as u64;
    if pitch < MIN_PITCH_UM as u64 || pitch > MAX_PITCH_UM as u64 {
        let (l, ls, at) = later(short_at, long_at);
        let kind = LevelErrorKind::PitchOutOfRange {
            short_um: spec.short_um,
            long_um: spec.long_um,
        };
        return err(if l == 0 { 1 } else { l }, b, ls, at, kind);
    }
    if 2 * spec.radius_um as u64 >= spec.long_um as u64 {
        let (l, ls, at) = later(radius_at, long_at);
        let kind = LevelErrorKind::MarbleTooBig {
            radius_um: spec.radius_um,
            long_um: spec.long_um,
        };
        return err(if l == 0 { 1 } else { l }, b, ls, at, kind);
    }
    // Grid: storeys top to bottom (`t` from the top; storey `n` from the bottom).
    let (nx, nz, storeys) = grid_shape(b, i);
    if nx == 0 {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::EmptyGrid,
        });
    }
    if nx > MAX_TILES_XZ || nz > MAX_TILES_XZ {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::TooLarge,
        });
    }
    // Past MAX_STOREYS the loop below stops at the separator that starts one too
    // many, having read the first ones as the storeys a grid can hold.
    let storeys = if storeys > MAX_STOREYS {
        MAX_STOREYS
    } else {
        storeys
    };
    let layers = 2 * storeys;
    let mut grid = match TileGrid::<WORDS>::new(nx, layers, if nz == 0 { 1 } else { nz }) {
        Ok(g) => g,
        Err(_) => {
            return Err(LevelError {
                line: line as u32,
                column: 1,
                kind: LevelErrorKind::TooLarge,
            })
        }
    };
    let mut starts = [Cell::new(0, 0, 0); MAX_MARBLES];
    let mut n_starts = 0usize;
    let mut goals = [Cell::new(0, 0, 0); MAX_GOALS];
    let mut n_goals = 0usize;
    let mut holes = storeys > 1;
    let mut t = 0usize;
    let mut k = 0usize;
    let mut last_row_line = line;
    while i < b.len() {
        let e = line_end(b, i);
        let end = trim_end(b, i, e);
        if end > i && is_separator(b, i, end) {
            if k == 0 {
                return err(line, b, i, i, LevelErrorKind::EmptyStorey);
            }
            if k != nz {
                return err(line, b, i, i, LevelErrorKind::StoreyRows);
            }
            t += 1;
            if t >= MAX_STOREYS {
                return err(line, b, i, i, LevelErrorKind::TooManyStoreys);
            }
            k = 0;
        } else if end > i {
            if k >= nz {
                return err(line, b, i, i, LevelErrorKind::StoreyRows);
            }
            let n = storeys - 1 - t;
            let (slab, walls) = (2 * n, 2 * n + 1);
            let mut col = 0usize;
            let mut p = i;
            while p < end {
                let c = b[p];
                if col >= nx {
                    return err(line, b, i, p, LevelErrorKind::RaggedRow);
                }
                let cell = col % 2 == 1 && k % 2 == 1;
                match c {
                    b'#' => {
                        // The storey above is already read: no slab there is its `O`.
                        if n + 1 < storeys && !grid.is_set(col, slab + 2, k) {
                            return err(line, b, i, p, LevelErrorKind::HoleAboveWall);
                        }
                        grid.set(col, slab, k, true);
                        grid.set(col, walls, k, true);
                    }
                    b'.' => {
                        grid.set(col, slab, k, true);
                    }
                    b'O' => holes = true,
                    b'S' | b'G' => {
                        if !cell {
                            return err(line, b, i, p, LevelErrorKind::NotACell);
                        }
                        grid.set(col, slab, k, true);
                        let at = Cell::new(col as u8, k as u8, n as u8);
                        if c == b'S' {
                            if n_starts == MAX_MARBLES {
                                return err(line, b, i, p, LevelErrorKind::StartCount);
                            }
                            starts[n_starts] = at;
                            n_starts += 1;
                        } else {
                            if n_goals == MAX_GOALS {
                                return err(line, b, i, p, LevelErrorKind::GoalCount);
                            }
                            goals[n_goals] = at;
                            n_goals += 1;
                        }
                    }
                    _ => return err(line, b, i, p, LevelErrorKind::BadTile),
                }
                // Advance one character (multi-byte ones are reported above as BadTile).
                p += 1;
                col += 1;
            }
            if col != nx {
                return err(line, b, i, end, LevelErrorKind::RaggedRow);
            }
            k += 1;
            last_row_line = line;
        }
        i = e + 1;
        line += 1;
    }
    if t > 0 && k == 0 {
        return Err(LevelError {
            line: last_row_line as u32 + 1,
            column: 1,
            kind: LevelErrorKind::EmptyStorey,
        });
    }
    if k != nz {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::StoreyRows,
        });
    }
    if n_starts == 0 {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::StartCount,
        });
    }
    if n_goals == 0 {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::GoalCount,
        });
    }
    effects.holes = holes;
    effects.marbles = n_starts > 1;
    spec.effects = effects;
    Ok(Level {
        info: LevelInfo {
            name,
            spec,
            time_limit_s,
            nx: nx as u8,
            nz: nz as u8,
            storeys: storeys as u8,
            starts,
            n_starts: n_starts as u8,
            goals,
            n_goals: n_goals as u8,
        },
        grid,
    })
}

#[doc(hidden)]
pub use const_panic as __const_panic;

/// A built-in level, parsed at compile time into a `'static` [`LevelView`]. A
/// malformed level stops the build with its line, column and what is wrong:
///
/// ```compile_fail
/// static BAD: marble_rolling::game::level::LevelView<'static> =
///     marble_rolling::builtin_level!("---\n#####\n#SxG#\n#####\n");
/// // error: built-in level: line 3, column 3: unknown tile (use # . O S G)
/// ```
///
/// ```
/// static OK: marble_rolling::game::level::LevelView<'static> =
///     marble_rolling::builtin_level!("---\n#####\n#S.G#\n#####\n");
/// assert_eq!(OK.info.goals(), &[marble_rolling::game::level::Cell::new(3, 1, 0)]);
/// ```
#[macro_export]
macro_rules! builtin_level {
    ($src:expr) => {{
        const SRC: &str = $src;
        const LEVEL: $crate::game::level::Level<
            'static,
            { $crate::game::level::words_needed(SRC) },
        > = match $crate::game::level::parse(SRC) {
            Ok(l) => l,
            Err(e) => $crate::game::level::__const_panic::concat_panic!(
                "built-in level: line ",
                e.line,
                ", column ",
                e.column,
                ": ",
                e.kind.message(),
                if e.kind.detail().is_empty() { "" } else { ": " },
                e.kind.detail()
            ),
        };
        // The name and the grid get constants of their own: the view must not
        // point into `SRC` or into `LEVEL` (whose name does), or the level's
        // whole text stays in flash (about 2 KB for the built-in levels).
        const NAME_BYTES: [u8; LEVEL.info.name.len()] =
            $crate::game::level::name_bytes(LEVEL.info.name);
        const NAME: &str = match ::core::str::from_utf8(&NAME_BYTES) {
            Ok(name) => name,
            Err(_) => panic!("built-in level: the name is not UTF-8"),
        };
        const GRID: $crate::game::level::BuiltinGrid<{ $crate::game::level::words_needed(SRC) }> =
            LEVEL.grid;
        let mut info = LEVEL.info;
        info.name = NAME;
        $crate::game::level::LevelView {
            info,
            tiles: GRID.view(),
        }
    }};
}

/// The grid of a built-in level ([`builtin_level!`]).
#[doc(hidden)]
pub type BuiltinGrid<const WORDS: usize> = TileGrid<WORDS>;

/// `name`'s bytes in an array of their own ([`builtin_level!`]): `N` must be
/// `name.len()`.
#[doc(hidden)]
pub const fn name_bytes<const N: usize>(name: &str) -> [u8; N] {
    let bytes = name.as_bytes();
    let mut out = [0u8; N];
    let mut n = 0;
    while n < N && n < bytes.len() {
        out[n] = bytes[n];
        n += 1;
    }
    out
}
