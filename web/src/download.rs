//! The editor's "Download for micro:bit": the level typed into the editor,
//! checked for each micro:bit, written as a levels region
//! (`game::levels_region::write`, the writer `cargo xtask hex --level` uses)
//! into the universal hex the page serves ([`crate::universal_hex`]). The
//! page writes that hex into [`hex_ptr`]'s buffer and the level into the text
//! buffer, calls [`download_hex`] and saves what [`hex_out_ptr`] holds.
//!
//! A level goes into both boards' regions when the v2 can show it: a
//! micro:bit v1 skips one larger than its maze slot (it plays the built-in
//! levels), which [`download_note`] tells the player; a level neither board
//! can show, or one the region cannot hold, is an error naming why.

use core::cell::{Cell, UnsafeCell};

use marble_rolling::board::levels_region::{self, WriteError, SIZE, V1, V2};
use marble_rolling::board::{microbit, microbit_v1};
use marble_rolling::game::endless::Reach;
use marble_rolling::game::level::{parse, text as level_text, words_needed, LevelError};

use crate::storage::{answer, text, TextError, MAX_WORDS, TEXT, TEXT_CUT};
use crate::universal_hex::{self, HexError, Patch, BOARD_V1, BOARD_V2};
use crate::Single;

/// Bytes of the served hex the page can hand over, and of the result: the
/// universal hex is about 600 KB (both boards' images, 144 KiB of flash at
/// most on each); a region adds at most 11 KB a board. Zeroed statics: they
/// cost the module no bytes, the page's memory 2 MiB.
pub(crate) const HEX_CAPACITY: usize = 1 << 20;

static HEX: Single<UnsafeCell<[u8; HEX_CAPACITY]>> = Single(UnsafeCell::new([0; HEX_CAPACITY]));
static HEX_OUT: Single<UnsafeCell<[u8; HEX_CAPACITY]>> = Single(UnsafeCell::new([0; HEX_CAPACITY]));

/// What the last successful [`download_hex`] has to tell: that the v1
/// cannot show the level, if it cannot.
static NOTE: Single<Cell<Option<Unshown>>> = Single(Cell::new(None));

/// The level is too large for the micro:bit v1 (the v2's slot is the larger:
/// a level the v1 holds, the v2 holds too): the words it needs, the words the
/// v1 holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Unshown {
    needs: usize,
    room: usize,
}

const _: () = assert!(V2_WORDS >= V1_WORDS);

/// A download written: its length, whether the v1 cannot show the level and
/// the level's name.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct Downloaded<'t> {
    pub(crate) len: usize,
    pub(crate) note: Option<Unshown>,
    pub(crate) name: &'t str,
}

/// Where the level's name is in the text buffer after a successful
/// [`download_hex`] (offset, length): the page names the file after it.
static NAME: Single<Cell<(usize, usize)>> = Single(Cell::new((0, 0)));

/// A micro:bit the download is for.
struct Board {
    name: &'static str,
    block: u16,
    region: core::ops::Range<u32>,
    /// The largest maze its slot keeps: the largest level it shows.
    reach: Reach,
}

const BOARDS: [Board; 2] = [
    Board {
        name: "micro:bit v1",
        block: BOARD_V1,
        region: V1,
        reach: microbit_v1::MAZE_REACH,
    },
    Board {
        name: "micro:bit v2",
        block: BOARD_V2,
        region: V2,
        reach: microbit::MAZE_REACH,
    },
];

/// The occupancy words each board's slot holds, as its firmware parses a
/// region's level (`MazeSlot::load`).
const V1_WORDS: usize = microbit_v1::MAZE_REACH.words();
const V2_WORDS: usize = microbit::MAZE_REACH.words();

/// Why there is no download.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum DownloadError {
    /// The level's own error, as the editor shows it.
    Level(LevelError),
    /// The text is longer than the editor takes.
    TooLong,
    /// Neither board can show it: the words it needs, each board's.
    TooLarge { needs: usize },
    /// The region cannot hold its text.
    Region { needs: usize },
    /// The page handed over more hex than the buffer holds.
    HexTooLong { len: usize },
    /// The served hex is not one the page can patch.
    Hex(HexError),
}

/// "15 × 15 tiles on 4 storeys": what a reach shows, in the level format's terms.
struct Tiles(Reach);

impl core::fmt::Display for Tiles {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let side = 2 * usize::from(self.0.size) + 1;
        let storeys = self.0.storeys;
        write!(f, "{side} × {side} tiles on {storeys} storeys")
    }
}

impl core::fmt::Display for DownloadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DownloadError::Level(e) => write!(f, "{e}"),
            DownloadError::TooLong => write!(f, "{}", TextError::TooLong),
            DownloadError::TooLarge { needs } => {
                let [v1, v2] = &BOARDS;
                write!(
                    f,
                    "too large for a micro:bit: the level needs {needs} occupancy words of \
                     tiles; the {} holds {V1_WORDS} ({}), the {} {V2_WORDS} ({})",
                    v1.name,
                    Tiles(v1.reach),
                    v2.name,
                    Tiles(v2.reach)
                )
            }
            DownloadError::Region { needs } => write!(
                f,
                "too long for the levels region: the level's text takes {needs} B there \
                 (with the {} B header and its 2 B length), the region holds {SIZE} B",
                levels_region::HEADER
            ),
            DownloadError::HexTooLong { len } => write!(
                f,
                "the served .hex is {len} B, the page takes up to {HEX_CAPACITY} B"
            ),
            DownloadError::Hex(e) => write!(f, "the served .hex: {e}"),
        }
    }
}

/// The universal hex `hex` with `level` in both boards' levels regions,
/// written into `out`.
///
/// The level is parsed once, into the editor's grid (the parser the module
/// links already: one more of a board's size is kilobytes of the module), and
/// held against each board's slot by its words, the test
/// `levels_region::level` makes for "too large" on the boards.
pub(crate) fn download<'t>(
    level: &'t [u8],
    hex: &[u8],
    out: &mut [u8],
) -> Result<Downloaded<'t>, DownloadError> {
    let source = level_text(level).map_err(DownloadError::Level)?;
    let name = parse::<MAX_WORDS>(source)
        .map_err(DownloadError::Level)?
        .info
        .name;
    let needs = words_needed(source);
    if needs > V2_WORDS {
        return Err(DownloadError::TooLarge { needs });
    }
    let note = (needs > V1_WORDS).then_some(Unshown {
        needs,
        room: V1_WORDS,
    });
    let mut region = [0xFF; SIZE];
    let used = levels_region::write(&[level], &mut region).map_err(|e| match e {
        WriteError::TooBig { needs, .. } => DownloadError::Region { needs },
        WriteError::TooLong { .. } | WriteError::Count(_) => DownloadError::Region {
            needs: levels_region::HEADER + 2 + level.len(),
        },
    })?;
    let patches = BOARDS.map(|board| Patch {
        block: board.block,
        region: board.region,
        bytes: &region[..used],
    });
    let len = universal_hex::patch(hex, &patches, out).map_err(DownloadError::Hex)?;
    Ok(Downloaded { len, note, name })
}

/// Where the page writes the universal hex it serves.
#[no_mangle]
pub extern "C" fn hex_ptr() -> *mut u8 {
    HEX.0.get().cast()
}

/// How many bytes [`hex_ptr`]'s buffer holds.
#[no_mangle]
pub extern "C" fn hex_capacity() -> u32 {
    HEX_CAPACITY as u32
}

/// Where [`download_hex`] writes the file to save.
#[no_mangle]
pub extern "C" fn hex_out_ptr() -> *const u8 {
    HEX_OUT.0.get().cast_const().cast()
}

/// The `text_len` bytes of level text (as [`crate::storage::check_level`]
/// takes them) patched into the `hex_len` bytes of universal hex: the
/// length of the file at [`hex_out_ptr`], or minus the length of the error
/// in the answer buffer (`line:column: message` for the level's own error).
#[no_mangle]
pub extern "C" fn download_hex(text_len: u32, hex_len: u32) -> i32 {
    NOTE.0.set(None);
    NAME.0.set((0, 0));
    let result = if text_len & TEXT_CUT != 0 {
        Err(DownloadError::TooLong)
    } else if hex_len as usize > HEX_CAPACITY {
        Err(DownloadError::HexTooLong {
            len: hex_len as usize,
        })
    } else {
        match text(text_len) {
            Err(TextError::TooLong) => Err(DownloadError::TooLong),
            Err(TextError::Level(e)) => Err(DownloadError::Level(e)),
            Ok(level) => {
                // SAFETY: single thread (see `Single`): the page writes HEX
                // only between calls, and nothing else borrows either buffer.
                let (hex, out) = unsafe { (&*HEX.0.get(), &mut *HEX_OUT.0.get()) };
                download(level.as_bytes(), &hex[..hex_len as usize], out).map(|done| {
                    // The name borrows the text: where it is in it.
                    let at = done.name.as_ptr() as usize - level.as_ptr() as usize;
                    (done.len, done.note, (at, done.name.len()))
                })
            }
        }
    };
    match result {
        Ok((len, note, name)) => {
            NOTE.0.set(note);
            NAME.0.set(name);
            len as i32
        }
        Err(e) => -(answer(format_args!("{e}")) as i32),
    }
}

/// After a [`download_hex`] that succeeded: the length of what the player
/// should know in the answer buffer (the board that cannot show the level),
/// or 0.
#[no_mangle]
pub extern "C" fn download_note() -> u32 {
    match NOTE.0.get() {
        None => 0,
        Some(note) => answer(format_args!("{}", Note(note))),
    }
}

/// After a [`download_hex`] that succeeded: the length of the level's name
/// in the answer buffer ("" after one that failed).
#[no_mangle]
pub extern "C" fn download_name() -> u32 {
    let (at, len) = NAME.0.get();
    // SAFETY: single thread (see `Single`); the buffer is only read here.
    let text: &[u8] = unsafe { &*TEXT.0.get() };
    // The page may have written other text since: whatever is there, as text.
    let name = text.get(at..at + len).unwrap_or_default();
    answer(format_args!(
        "{}",
        core::str::from_utf8(name).unwrap_or_default()
    ))
}

/// That the v1 cannot show the level, in words.
struct Note(Unshown);

impl core::fmt::Display for Note {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Unshown { needs, room } = self.0;
        let [board, _] = &BOARDS;
        write!(
            f,
            "a {} cannot show this level: it needs {needs} occupancy words of tiles, \
             the {} holds {room} ({}); it plays its built-in levels",
            board.name,
            board.name,
            Tiles(board.reach)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A universal hex of one byte per board (sections not yet aligned: the
    /// patch aligns the ones it writes).
    const HEX: &str = ":020000040000FA\n:0400000A9900C0DEBB\n:0100000042BD\n:0000000BF5\n\
                       :020000040000FA\n:0400000A9903C0DEB8\n:0100000D42B0\n:0000000BF5\n\
                       :00000001FF\n";

    /// The bytes of each block type's section, by address.
    fn images(text: &str) -> BTreeMap<u16, BTreeMap<u32, u8>> {
        let mut images: BTreeMap<u16, BTreeMap<u32, u8>> = BTreeMap::new();
        let (mut block, mut upper) = (0, 0);
        for line in text.lines() {
            let b: Vec<u8> = (1..line.len())
                .step_by(2)
                .map(|i| u8::from_str_radix(&line[i..i + 2], 16).unwrap())
                .collect();
            let (offset, data) = (u32::from(b[1]) << 8 | u32::from(b[2]), &b[4..b.len() - 1]);
            match b[3] {
                0x04 => upper = u32::from(data[0]) << 24 | u32::from(data[1]) << 16,
                0x0A => block = u16::from(data[0]) << 8 | u16::from(data[1]),
                0x00 | 0x0D => {
                    for (i, byte) in data.iter().enumerate() {
                        images
                            .entry(block)
                            .or_default()
                            .insert(upper + offset + i as u32, *byte);
                    }
                }
                _ => {}
            }
        }
        images
    }

    fn region_of(image: &BTreeMap<u32, u8>, at: u32) -> Vec<u8> {
        (at..at + SIZE as u32)
            .map(|a| image.get(&a).copied().unwrap_or(0xFF))
            .collect()
    }

    /// An open room `n` tiles a side, one storey.
    fn room(n: usize) -> String {
        let wall = "#".repeat(n);
        let mut rows = vec![wall.clone()];
        for k in 1..n - 1 {
            let (first, last) = (
                if k == 1 { 'S' } else { '.' },
                if k == n - 2 { 'G' } else { '.' },
            );
            rows.push(format!("#{first}{}{last}#", ".".repeat(n - 4)));
        }
        rows.push(wall);
        format!("name: room-{n}\n---\n{}\n", rows.join("\n"))
    }

    fn run(level: &str) -> Result<(String, Option<String>), String> {
        let mut out = vec![0; 1 << 16];
        download(level.as_bytes(), HEX.as_bytes(), &mut out)
            .map(|done| {
                let text = String::from_utf8(out[..done.len].to_vec()).unwrap();
                (text, done.note.map(|n| Note(n).to_string()))
            })
            .map_err(|e| e.to_string())
    }

    #[test]
    fn the_level_is_in_both_regions_as_the_firmware_reads_it() {
        let level = room(9);
        let (text, note) = run(&level).unwrap();
        assert_eq!(note, None);
        let mut out = vec![0; 1 << 16];
        let done = download(level.as_bytes(), HEX.as_bytes(), &mut out).unwrap();
        assert_eq!(done.name, "room-9");
        let images = images(&text);
        for (block, at) in [(BOARD_V1, V1.start), (BOARD_V2, V2.start)] {
            let bytes = region_of(&images[&block], at);
            let region = levels_region::read(&bytes).expect("a region the firmware takes");
            assert_eq!(region.len(), 1);
            assert_eq!(region.bytes(0), Some(level.as_bytes()), "{block:04X}");
            assert_eq!(images[&block][&0], 0x42, "{block:04X}'s own byte");
        }
    }

    #[test]
    fn a_level_too_large_for_the_v1_goes_with_a_note() {
        // 31 × 31 tiles on one storey: 61 words, the v1 holds 57, the v2 111.
        let (text, note) = run(&room(31)).unwrap();
        assert_eq!(
            note.as_deref(),
            Some(
                "a micro:bit v1 cannot show this level: it needs 61 occupancy words of tiles, \
                 the micro:bit v1 holds 57 (15 × 15 tiles on 4 storeys); it plays its \
                 built-in levels"
            )
        );
        assert!(levels_region::read(&region_of(&images(&text)[&BOARD_V1], V1.start)).is_ok());
    }

    #[test]
    fn errors_say_what_is_wrong() {
        assert_eq!(
            run(&room(61)).unwrap_err(),
            "too large for a micro:bit: the level needs 233 occupancy words of tiles; the \
             micro:bit v1 holds 57 (15 × 15 tiles on 4 storeys), the micro:bit v2 111 \
             (21 × 21 tiles on 4 storeys)"
        );
        let long_name = format!("name: {}\n---\n#####\n#S.G#\n#####\n", "a".repeat(4100));
        assert_eq!(
            run(&long_name).unwrap_err(),
            format!(
                "too long for the levels region: the level's text takes {} B there (with the \
                 16 B header and its 2 B length), the region holds 4096 B",
                long_name.len() + 18
            )
        );
        assert_eq!(
            run("---\n#####\n#SxG#\n#####\n").unwrap_err(),
            "3:3: unknown tile (use # . O S G)"
        );
        let mut out = vec![0; 1 << 16];
        let broken = HEX.replace(":0100000042BD", ":0100000042BE");
        let error = download(room(9).as_bytes(), broken.as_bytes(), &mut out).unwrap_err();
        assert_eq!(error.to_string(), "the served .hex: line 3: wrong checksum");
    }
}
