//! The endless run: first the levels of the board's levels region
//! ([`crate::game::levels_region`], the player's own, if there are any), then
//! the built-in levels, then generated mazes ([`crate::game::generate`]) of
//! rising difficulty, for as long as the player plays.
//!
//! Which level is the `n`-th of a run is a pure function ([`Endless::stage`]):
//! the region's levels first, then the built-in levels, then maze
//! `k = n − region levels − built-ins` with
//!
//! * **storeys** going round `1 ..= reach.storeys` (a board that shows one storey
//!   plays one),
//! * **size** [`FIRST_SIZE`] cells a side, one more after each round of storeys,
//!   up to `reach.size`,
//! * **difficulty** `1 + k / 2` up to [`MAX_DIFFICULTY`] (friction from the first
//!   maze, as the last built-in levels have; pits from the third; more marbles,
//!   board motion and tighter time limits later: see the generator),
//! * **seed** the level's number in the run (1-based, the region's levels not
//!   counted, so that the mazes are the same with or without them) with
//!   [`Seeds::Count`], so a board without a random source (QEMU, the micro:bit
//!   v1) and its demo play the same mazes every time, or a number drawn once at
//!   power-up with [`Seeds::Drawn`] (the micro:bit v2's RNG), so that each
//!   power-up differs.
//!
//! A board can keep only mazes up to some size and storeys in RAM: its
//! [`Reach`]. The maze being played is kept in a [`MazeSlot`] sized for that
//! reach: the generator writes the maze's level text into a buffer on the stack,
//! the text is parsed exactly as `cargo sim -- --generate …` parses it, and only
//! the parsed tiles, the header and the name stay (the text is dropped). So a
//! board's maze ends on the same `state_hash` as `cargo sim -- --generate SEED
//! --size N --storeys S --difficulty D --autopilot` for the same stepping.
//!
//! A level of the region is parsed into the same slot ([`MazeSlot::load`]), as
//! `cargo sim -- --check` parses a file; its name stays in the region's flash.
//! One the board cannot hold, or that does not parse, is skipped
//! ([`StageError::Skipped`] says which and why), never played in part.

use core::fmt::{self, Write};

use super::generate::{self, GenerateError, Maze, MAX_DIFFICULTY, MAX_SIZE, MIN_SIZE};
use super::level::{parse, LevelError, LevelInfo, LevelView};
use super::levels::LEVELS;
use crate::game::levels_region::{self, LevelCheck, Region};
use crate::physics::geometry::grid::{words_for, TileGrid};

/// Generated mazes the headless demos play after the built-in levels.
pub const DEMO_MAZES: usize = 3;

/// Cells a side of the first generated mazes.
pub const FIRST_SIZE: u8 = 4;

/// The most storeys a generated maze can have in this build (the generator's
/// range: 1 without the feature `storeys`).
pub(crate) const MOST_STOREYS: u8 = if cfg!(feature = "storeys") {
    crate::physics::geometry::grid::MAX_STOREYS as u8
} else {
    1
};

/// Bytes a [`MazeSlot`] keeps for the maze's name: the longest,
/// `maze-4294967295-15x15x4-d9`, is 26.
const NAME_BYTES: usize = 28;

/// The largest maze a board plays: cells a side and storeys. Sizes its
/// [`MazeSlot`] ([`Reach::words`], [`Reach::text_bytes`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reach {
    /// Cells along a side, at most ([`MIN_SIZE`] ..= [`MAX_SIZE`]).
    pub size: u8,
    /// Storeys, at most (1 ..= `MOST_STOREYS`).
    pub storeys: u8,
}

impl Reach {
    /// Occupancy words of the largest maze within reach (`2 size + 1` tiles a
    /// side, two layers a storey).
    pub const fn words(self) -> usize {
        let tiles = 2 * self.size as usize + 1;
        words_for(tiles, 2 * self.storeys as usize, tiles)
    }

    /// Bytes of the longest level text of a maze within reach.
    pub const fn text_bytes(self) -> usize {
        generate::text_bytes(self.size, self.storeys)
    }

    /// The reach as the generator can make it: the size within
    /// [`MIN_SIZE`] ..= [`MAX_SIZE`], the storeys within 1 ..= [`MOST_STOREYS`].
    const fn bounded(self) -> Reach {
        Reach {
            size: clamp(self.size, MIN_SIZE, MAX_SIZE),
            storeys: clamp(self.storeys, 1, MOST_STOREYS),
        }
    }

    /// Whether a maze of `args` is within reach.
    pub const fn holds(self, args: MazeArgs) -> bool {
        args.size <= self.size && args.storeys <= self.storeys
    }
}

const fn clamp(n: u8, low: u8, high: u8) -> u8 {
    if n < low {
        low
    } else if n > high {
        high
    } else {
        n
    }
}

/// Where the seeds of a run's mazes come from.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Seeds {
    /// The level's number in the run, 1-based (the first maze after ten built-in
    /// levels is seed 11): the same mazes on every run.
    Count,
    /// From a number drawn at power-up: maze `k` gets `drawn + k · 0x9E37_79B9`
    /// (wrapping). The odd step gives every maze of a run its own seed, and
    /// runs from two draws that are close do not share their mazes.
    Drawn(u32),
}

/// A generated maze's arguments, as `cargo sim -- --generate SEED --size N
/// --storeys S --difficulty D` takes them.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MazeArgs {
    /// The generator's seed.
    pub seed: u32,
    /// Cells along a side.
    pub size: u8,
    /// Storeys.
    pub storeys: u8,
    /// Difficulty, 0 ..= [`MAX_DIFFICULTY`].
    pub difficulty: u8,
}

/// The maze's name, as its level text names it (`maze-SEED-NxNxS-dD`).
impl fmt::Display for MazeArgs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        generate::write_name(f, self.seed, self.size, self.storeys, self.difficulty)
    }
}

/// What the `n`-th level of a run is.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// The level of this index (from 0) in the levels region.
    Region(usize),
    /// The built-in level of this index.
    Builtin(usize),
    /// A generated maze.
    Maze(MazeArgs),
}

/// A board's endless run (see the module documentation).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Endless {
    /// Levels of the levels region before the built-in ones (0 without a
    /// region: [`Region::len`]).
    pub from_region: usize,
    /// Built-in levels before the first maze.
    pub builtins: usize,
    /// The largest maze the board keeps.
    pub reach: Reach,
    /// Where the mazes' seeds come from.
    pub seeds: Seeds,
}

impl Endless {
    /// A board's run: the levels of `region` (its levels region as
    /// [`levels_region::at_boot`] found it; `None`: no levels of the
    /// player's), the built-in levels, then mazes within `reach` with seeds
    /// from `seeds`.
    pub fn new(region: Option<Region<'_>>, reach: Reach, seeds: Seeds) -> Self {
        Endless {
            from_region: region.map_or(0, |region| region.len()),
            builtins: LEVELS.len(),
            reach,
            seeds,
        }
    }

    /// Level `number` of the run (counted from 0): a level of the region, a
    /// built-in level, or the maze that comes after the `number − 1` levels
    /// before it.
    pub fn stage(&self, number: usize) -> Stage {
        // The region's levels come first and do not move the mazes' seeds.
        let Some(number) = number.checked_sub(self.from_region) else {
            return Stage::Region(number);
        };
        let Some(k) = number.checked_sub(self.builtins) else {
            return Stage::Builtin(number);
        };
        let reach = self.reach.bounded();
        let round = k / usize::from(reach.storeys);
        let storeys = 1 + (k % usize::from(reach.storeys)) as u8;
        let size = usize::from(FIRST_SIZE)
            .saturating_add(round)
            .min(usize::from(reach.size)) as u8;
        let difficulty = (1 + k / 2).min(usize::from(MAX_DIFFICULTY)) as u8;
        let seed = match self.seeds {
            // A run past four thousand million levels starts its seeds again.
            Seeds::Count => number.wrapping_add(1) as u32,
            Seeds::Drawn(drawn) => drawn.wrapping_add((k as u32).wrapping_mul(0x9E37_79B9)),
        };
        Stage::Maze(MazeArgs {
            seed,
            size,
            storeys,
            difficulty,
        })
    }

    /// The generated maze that level `number` of the run is, if it is one.
    pub fn maze(&self, number: usize) -> Option<MazeArgs> {
        match self.stage(number) {
            Stage::Maze(args) => Some(args),
            Stage::Builtin(_) | Stage::Region(_) => None,
        }
    }

    /// The built-in level that level `number` of the run is, if it is one (its
    /// index in [`LEVELS`]: the best times are kept by it).
    pub fn builtin(&self, number: usize) -> Option<usize> {
        match self.stage(number) {
            Stage::Builtin(index) => Some(index),
            Stage::Region(_) | Stage::Maze(_) => None,
        }
    }

    /// Level `number` of the run ([`Endless::stage`]): a level of the
    /// slot's region parsed into `mazes` ([`MazeSlot::load`]), a built-in level of
    /// [`LEVELS`], or the maze made in `mazes` ([`MazeSlot::make`]).
    pub fn level<'m, const WORDS: usize, const TEXT: usize>(
        &self,
        number: usize,
        mazes: &'m mut MazeSlot<WORDS, TEXT>,
    ) -> Result<LevelView<'m>, StageError<'static>> {
        match self.stage(number) {
            Stage::Region(index) => {
                let text = mazes
                    .region()
                    .and_then(|region| region.bytes(index))
                    .ok_or(StageError::NoRegionLevel(index))?;
                mazes.load(text).map_err(|why| StageError::Skipped {
                    index,
                    name: name_of(text),
                    why,
                })
            }
            Stage::Builtin(index) => LEVELS
                .get(index)
                .copied()
                .ok_or(StageError::NoBuiltin(index)),
            Stage::Maze(args) => mazes.make(args).map_err(StageError::Maze),
        }
    }
}

/// Why [`Endless::level`] gives no level.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StageError<'t> {
    /// Level `index` (from 0) of the levels region is not played: it does not
    /// parse, or the board cannot hold it. Its caller skips it.
    Skipped {
        /// The level in the region.
        index: usize,
        /// Its name, if its header names it (for the log).
        name: Option<&'t str>,
        /// Why, as `cargo sim -- --check` says it (or too large for the board).
        why: LevelCheck,
    },
    /// The region has no level `index` ([`Endless::from_region`] counts more,
    /// or no region was given: a bug of the caller).
    NoRegionLevel(usize),
    /// [`LEVELS`] has no level `index` ([`Endless::builtins`] counts more).
    NoBuiltin(usize),
    /// The maze could not be made (a bug).
    Maze(MazeError),
}

impl fmt::Display for StageError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StageError::Skipped { index, name, why } => {
                write!(f, "level {} of the levels region", index + 1)?;
                if let Some(name) = name {
                    write!(f, " ({name})")?;
                }
                match why {
                    LevelCheck::Parse(e) => write!(f, " is skipped: {e}"),
                    LevelCheck::TooLarge { needs, room } => write!(
                        f,
                        " is skipped: it needs {needs} occupancy words, this board holds {room}"
                    ),
                }
            }
            StageError::NoRegionLevel(index) => {
                write!(f, "the levels region has no level {}", index + 1)
            }
            StageError::NoBuiltin(index) => write!(f, "there is no built-in level {}", index + 1),
            StageError::Maze(e) => write!(f, "{e}"),
        }
    }
}

/// The name a level text's header gives (`name: …` before `---`), for saying
/// which level of the region is skipped when it does not parse. `None` when
/// the header has none, or it is not UTF-8.
pub(crate) fn name_of(text: &[u8]) -> Option<&str> {
    for line in text.split(|&b| b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line == b"---" {
            break;
        }
        if let Some(value) = line.strip_prefix(b"name:") {
            return core::str::from_utf8(value).ok().map(str::trim_ascii);
        }
    }
    None
}

/// Why a [`MazeSlot`] holds no maze.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MazeError {
    /// The maze is larger than the slot's [`Reach`].
    BeyondReach(MazeArgs),
    /// The generator refused the arguments.
    Generate(GenerateError),
    /// The level text did not fit the text buffer (a bug in
    /// [`generate::text_bytes`]).
    TextTooLong,
    /// The text did not parse into the slot (a bug in the generator or in
    /// [`Reach::words`]).
    Level(LevelError),
    /// The maze's name did not fit the slot's name buffer.
    NameTooLong,
}

impl fmt::Display for MazeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MazeError::BeyondReach(args) => write!(
                f,
                "maze {} of {} cells a side on {} storeys is beyond this board's reach",
                args.seed, args.size, args.storeys
            ),
            MazeError::Generate(e) => write!(f, "{e}"),
            MazeError::TextTooLong => f.write_str("the maze's level text overflows its buffer"),
            MazeError::Level(e) => write!(f, "the maze's level text does not parse: {e}"),
            MazeError::NameTooLong => f.write_str("the maze's name overflows its buffer"),
        }
    }
}

impl From<GenerateError> for MazeError {
    fn from(e: GenerateError) -> Self {
        MazeError::Generate(e)
    }
}

/// Room for the generated maze being played, on a board that keeps mazes up to
/// a [`Reach`]: `WORDS` words of tiles ([`Reach::words`]), the header and the
/// maze's name, which the level made by [`MazeSlot::make`] borrows. The level
/// text, up to `TEXT` bytes ([`Reach::text_bytes`]), is on the stack only
/// while it is parsed.
#[derive(Clone, Debug)]
pub struct MazeSlot<const WORDS: usize, const TEXT: usize> {
    reach: Reach,
    /// The board's levels region, whose levels are parsed here in turn
    /// ([`MazeSlot::with_region`]).
    region: Option<Region<'static>>,
    name: [u8; NAME_BYTES],
    name_len: u8,
    /// The header (its name a placeholder: the name is `name`) and the tiles.
    level: Option<(LevelInfo<'static>, TileGrid<WORDS>)>,
}

impl<const WORDS: usize, const TEXT: usize> MazeSlot<WORDS, TEXT> {
    /// An empty slot for mazes within `reach`.
    pub const fn new(reach: Reach) -> Self {
        MazeSlot {
            reach,
            region: None,
            name: [0; NAME_BYTES],
            name_len: 0,
            level: None,
        }
    }

    /// The largest maze it keeps.
    pub const fn reach(&self) -> Reach {
        self.reach
    }

    /// The slot, with the levels of `region` to play first (the board's
    /// levels region as [`levels_region::at_boot`] found it, in flash for the
    /// firmware's lifetime). The region rides in the slot rather than as one
    /// more argument of the game's tasks: on the micro:bit v1 that argument
    /// made the compiler move the demo's 2 KiB future through the stack.
    pub const fn with_region(mut self, region: Option<Region<'static>>) -> Self {
        self.region = region;
        self
    }

    /// The levels region the slot was given ([`MazeSlot::with_region`]).
    pub const fn region(&self) -> Option<Region<'static>> {
        self.region
    }

    /// Generates the maze of `args`, writes its level text and parses it: the
    /// level kept here (whatever the slot held before is gone, also on an
    /// error). Out of line: the maze and its text take their stack only here,
    /// not in the game loop that calls it.
    #[inline(never)]
    pub fn make(&mut self, args: MazeArgs) -> Result<LevelView<'_>, MazeError> {
        self.level = None;
        if !self.reach.holds(args) {
            return Err(MazeError::BeyondReach(args));
        }
        let mut text = Text::<TEXT>::new();
        write_maze(args, &mut text)?;
        let level = parse::<WORDS>(text.as_str()).map_err(MazeError::Level)?;
        let name = level.info.name.as_bytes();
        let kept = self
            .name
            .get_mut(..name.len())
            .ok_or(MazeError::NameTooLong)?;
        kept.copy_from_slice(name);
        self.name_len = name.len() as u8;
        self.level = Some((level.info.renamed(""), level.grid));
        self.view().ok_or(MazeError::NameTooLong)
    }

    /// Parses level text `text` (a level of the levels region) into the
    /// slot, as `cargo sim -- --check` parses a file
    /// ([`levels_region::level`]): whatever the slot held before is gone, also
    /// on an error. The level's name is borrowed from `text` (the region's
    /// flash), not kept here. Out of line like [`MazeSlot::make`]: the parsed
    /// tiles pass through its stack only.
    #[inline(never)]
    pub fn load<'m, 't: 'm>(&'m mut self, text: &'t [u8]) -> Result<LevelView<'m>, LevelCheck> {
        self.level = None;
        self.name_len = 0;
        let level = levels_region::level::<WORDS>(text)?;
        let name = level.info.name;
        let (info, grid) = self.level.insert((level.info.renamed(""), level.grid));
        Ok(LevelView {
            info: info.renamed(name),
            tiles: grid.view(),
        })
    }

    /// The maze [`MazeSlot::make`] made last, if it made one (a level
    /// [`MazeSlot::load`] loaded, nameless: its name is in its text).
    pub(crate) fn view(&self) -> Option<LevelView<'_>> {
        let (info, grid) = self.level.as_ref()?;
        // The name was a `str`: its bytes are UTF-8.
        let name = self.name.get(..usize::from(self.name_len))?;
        let name = core::str::from_utf8(name).ok()?;
        Some(LevelView {
            info: info.renamed(name),
            tiles: grid.view(),
        })
    }
}

/// The maze of `args`'s level text into `text`. Out of line, so that the maze
/// (912 bytes of cells) is off the stack before the text is parsed.
#[inline(never)]
fn write_maze<const TEXT: usize>(args: MazeArgs, text: &mut Text<TEXT>) -> Result<(), MazeError> {
    let mut maze = Maze::EMPTY;
    maze.generate(args.seed, args.size, args.storeys, args.difficulty)?;
    maze.write_text(text).map_err(|_| MazeError::TextTooLong)
}

/// A level text being written: `N` bytes, and an error rather than a cut when
/// they are full (a cut text would be another level, or none).
struct Text<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

impl<const N: usize> Text<N> {
    fn new() -> Self {
        Text {
            bytes: [0; N],
            len: 0,
        }
    }

    fn as_str(&self) -> &str {
        // Only whole `str`s are ever written: the prefix is UTF-8.
        self.bytes
            .get(..self.len)
            .and_then(|b| core::str::from_utf8(b).ok())
            .unwrap_or("")
    }
}

impl<const N: usize> Write for Text<N> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len.checked_add(s.len()).ok_or(fmt::Error)?;
        let room = self.bytes.get_mut(self.len..end).ok_or(fmt::Error)?;
        room.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The arguments' name is the one the generated level text gives itself
    /// (the demos' checks look for it in the boards' `profile` lines).
    #[test]
    fn a_maze_is_named_by_its_arguments_as_its_text_names_it() {
        let cases = [(1, 7, 2, 9), (12, 4, 2, 1), (4_000_000, 15, 4, 0)];
        for (seed, size, storeys, difficulty) in cases {
            let args = MazeArgs {
                seed,
                size,
                storeys,
                difficulty,
            };
            let mut text = heapless::String::<4096>::new();
            let maze = generate::generate(seed, size, storeys, difficulty).expect("a maze");
            write!(text, "{maze}").expect("the text fits");
            let mut name = heapless::String::<32>::new();
            write!(name, "{args}").expect("the name fits");
            let first = text.lines().next().and_then(|l| l.strip_prefix("name: "));
            assert_eq!(first, Some(name.as_str()));
        }
        let mut name = heapless::String::<32>::new();
        let args = MazeArgs {
            seed: 3,
            size: 7,
            storeys: 2,
            difficulty: 9,
        };
        write!(name, "{args}").expect("the name fits");
        assert_eq!(name.as_str(), "maze-3-7x7x2-d9");
    }

    #[test]
    fn a_skipped_level_is_named_by_its_header_trimmed_of_ascii_blanks() {
        assert_eq!(name_of(b"name:  corner \t\r\n---\n#####"), Some("corner"));
        assert_eq!(name_of(b"effects: rolling\nname:x\n---"), Some("x"));
        assert_eq!(name_of(b"---\nname: below the grid"), None);
        assert_eq!(name_of(b"name: \xff\n---"), None);
        // Only ASCII blanks go, as the level parser trims them.
        assert_eq!(
            name_of("name:\u{a0}nbsp\n---".as_bytes()),
            Some("\u{a0}nbsp")
        );
    }

    #[test]
    fn a_full_text_fails_rather_than_cuts() {
        let mut text = Text::<4>::new();
        assert!(write!(text, "abc").is_ok());
        assert!(write!(text, "de").is_err());
        assert_eq!(text.as_str(), "abc");
    }
}
