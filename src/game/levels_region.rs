//! Your levels on the board: a region of each micro:bit's flash, at a fixed
//! address (`board::levels_region::V1`, `V2`), that holds up to [`MAX_LEVELS`] level texts for
//! the firmware to play before the built-in ones. `cargo xtask hex --level
//! FILE…` writes it into the .hex files ([`write()`]) and reads it back
//! from them with [`read`] in its check. Both micro:bits read it the same way
//! at boot ([`at_boot`]), each level with [`level`] when its turn comes
//! ([`crate::game::endless`]), and play none of the region, with one log line
//! saying why, when anything is wrong with it (a level that is wrong alone is
//! skipped alone): an erased region (no levels: a plain hex leaves it so), a foreign magic,
//! another version, a length past the region, a CRC that does not match, an
//! entry cut short, a level the parser refuses (the error `cargo sim --
//! --check` gives, at its line and column) or one larger than the board can
//! hold. Nothing here panics on any bytes.
//!
//! # Layout (little-endian)
//!
//! | offset | size | field |
//! |---:|---:|---|
//! | 0 | 4 | magic `MRLV` |
//! | 4 | 4 | CRC-32 (IEEE 802.3, zlib's `crc32`) of bytes 8 .. 16 + length |
//! | 8 | 1 | version, [`VERSION`] |
//! | 9 | 1 | number of levels, 1 ..= [`MAX_LEVELS`] |
//! | 10 | 2 | 0 (reserved) |
//! | 12 | 4 | length: the bytes of entries after the header |
//! | 16 | length | per level: its text's length (2 bytes), then the text (UTF-8) |
//!
//! The CRC covers the version, the count and the length too, so that a flipped
//! bit anywhere after the magic is caught; the length is checked against the
//! region before the CRC is computed over it. The region is one erase unit on
//! each board (four 1 KiB pages on the nRF51, one 4 KiB page on the nRF52), and
//! each board's `memory.x` keeps the linker out of it.

use crate::game::level::{parse, text, words_needed, Level, LevelError, LevelErrorKind};
use crate::physics::geometry::grid::{words_for, MAX_LAYERS, MAX_TILES_XZ};

/// The first bytes of a levels region.
pub const MAGIC: [u8; 4] = *b"MRLV";
/// The layout above.
pub const VERSION: u8 = 1;
/// Bytes before the entries.
pub const HEADER: usize = 16;
/// Bytes of the region on every board.
pub const SIZE: usize = 4096;
/// Most levels a region holds.
pub const MAX_LEVELS: usize = 8;
/// Why a region is not played.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RegionError {
    /// Erased flash (the magic reads `FF FF FF FF`): no levels were written.
    Erased,
    /// The first four bytes are neither [`MAGIC`] nor erased flash.
    Magic([u8; 4]),
    /// A version this firmware does not read.
    Version(u8),
    /// No levels, or more than [`MAX_LEVELS`].
    Count(u8),
    /// The length runs past the region (`room` bytes after the header).
    Length {
        /// The header's length.
        length: u32,
        /// The bytes there are after the header.
        room: usize,
    },
    /// The CRC does not match.
    Crc {
        /// The header's CRC.
        stored: u32,
        /// The CRC of the bytes.
        computed: u32,
    },
    /// Entry `index` (0-based) runs past the length, or is missing.
    Truncated {
        /// The entry.
        index: u8,
    },
    /// Bytes left after the last entry.
    Trailing {
        /// How many.
        bytes: u32,
    },
}

/// Why one level of a valid region is not played.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LevelCheck {
    /// The parser's error, as `cargo sim -- --check` reports it.
    Parse(LevelError),
    /// The level needs more occupancy words than the board holds.
    TooLarge {
        /// Words the level needs.
        needs: usize,
        /// Words the board has for it.
        room: usize,
    },
}

/// Why [`write()`] cannot make a region.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriteError {
    /// No levels, or more than [`MAX_LEVELS`].
    Count(usize),
    /// Level `index`'s text is longer than an entry can say (65 535 bytes).
    TooLong {
        /// The level.
        index: usize,
    },
    /// The region would need `needs` bytes; there are `room`.
    TooBig {
        /// Bytes the region needs.
        needs: usize,
        /// Bytes in the buffer.
        room: usize,
    },
}

/// A region whose header, CRC and entries are sound: its level texts, as
/// bytes (a text is checked with [`level`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region<'a> {
    count: u8,
    entries: &'a [u8],
}

impl<'a> Region<'a> {
    /// The number of levels.
    pub fn len(&self) -> usize {
        usize::from(self.count)
    }

    /// Whether there are none (never, for a region [`read`] returned).
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The bytes of level `index`, if there is one.
    pub fn bytes(&self, index: usize) -> Option<&'a [u8]> {
        let mut rest = self.entries;
        for at in 0..=index {
            let (length, after) = entry(rest)?;
            if at == index {
                return after.get(..length);
            }
            rest = after.get(length..)?;
        }
        None
    }
}

/// The length of the entry at the head of `bytes`, and what follows it.
fn entry(bytes: &[u8]) -> Option<(usize, &[u8])> {
    match bytes {
        [low, high, rest @ ..] => Some((usize::from(u16::from_le_bytes([*low, *high])), rest)),
        _ => None,
    }
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    let mut word = [0u8; 4];
    if let Some(field) = bytes.get(at..at + 4) {
        word.copy_from_slice(field);
    }
    u32::from_le_bytes(word)
}

/// Reads the region in `flash` (the whole region, or as much of it as there
/// is: a shorter slice is a region cut short).
pub fn read(flash: &[u8]) -> Result<Region<'_>, RegionError> {
    let mut magic = [0xFFu8; 4];
    for (to, from) in magic.iter_mut().zip(flash) {
        *to = *from;
    }
    if magic == [0xFF; 4] {
        return Err(RegionError::Erased);
    }
    if magic != MAGIC {
        return Err(RegionError::Magic(magic));
    }
    let room = flash.len().saturating_sub(HEADER);
    if flash.len() < HEADER {
        return Err(RegionError::Length { length: 0, room });
    }
    let length = u32_at(flash, 12);
    let end = match usize::try_from(length) {
        Ok(length) if length <= room => HEADER + length,
        _ => return Err(RegionError::Length { length, room }),
    };
    let stored = u32_at(flash, 4);
    let computed = crc32(&flash[8..end]);
    if stored != computed {
        return Err(RegionError::Crc { stored, computed });
    }
    if flash[8] != VERSION {
        return Err(RegionError::Version(flash[8]));
    }
    let count = flash[9];
    if count == 0 || usize::from(count) > MAX_LEVELS {
        return Err(RegionError::Count(count));
    }
    let entries = &flash[HEADER..end];
    let mut rest = entries;
    for index in 0..count {
        let (length, after) = entry(rest).ok_or(RegionError::Truncated { index })?;
        rest = after
            .get(length..)
            .ok_or(RegionError::Truncated { index })?;
    }
    if !rest.is_empty() {
        return Err(RegionError::Trailing {
            bytes: rest.len() as u32,
        });
    }
    Ok(Region { count, entries })
}

/// The region a board finds in its flash at boot (`flash`: the region's
/// [`SIZE`] bytes at `board::levels_region::V1` or `V2`): its levels, or `None`, with one log
/// line either way (an erased region is no levels of the player's, the rest
/// is a region refused). [`read`], so nothing here panics on any bytes.
pub fn at_boot(flash: &[u8]) -> Option<Region<'_>> {
    match read(flash) {
        Ok(region) => {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "levels region: {=usize} level(s), played before the built-in ones",
                region.len()
            );
            Some(region)
        }
        Err(RegionError::Erased) => {
            #[cfg(feature = "defmt")]
            defmt::info!("levels region: erased, no levels of yours");
            None
        }
        Err(e) => {
            #[cfg(feature = "defmt")]
            defmt::warn!("levels region ignored: {}", e);
            let _ = e;
            None
        }
    }
}

/// Level text `bytes` parsed as `cargo sim -- --check` parses a file (bytes
/// that are not UTF-8 included), into a grid of `WORDS` occupancy words: a
/// level the format allows but that needs more words is
/// [`LevelCheck::TooLarge`] for this board (the parser would only say "too
/// large" at its first grid line).
pub fn level<const WORDS: usize>(bytes: &[u8]) -> Result<Level<'_, WORDS>, LevelCheck> {
    let src = text(bytes).map_err(LevelCheck::Parse)?;
    match parse::<WORDS>(src) {
        Err(e) if e.kind == LevelErrorKind::TooLarge => {
            let needs = words_needed(src);
            let format_allows = words_for(MAX_TILES_XZ, MAX_LAYERS, MAX_TILES_XZ);
            if needs > WORDS && needs <= format_allows {
                Err(LevelCheck::TooLarge { needs, room: WORDS })
            } else {
                Err(LevelCheck::Parse(e))
            }
        }
        parsed => parsed.map_err(LevelCheck::Parse),
    }
}

/// Writes a region of `texts` into `out` (erased bytes, `0xFF`, after it);
/// returns the bytes used.
pub fn write(texts: &[&[u8]], out: &mut [u8]) -> Result<usize, WriteError> {
    if texts.is_empty() || texts.len() > MAX_LEVELS {
        return Err(WriteError::Count(texts.len()));
    }
    let mut needs = HEADER;
    for (index, text) in texts.iter().enumerate() {
        if text.len() > usize::from(u16::MAX) {
            return Err(WriteError::TooLong { index });
        }
        needs += 2 + text.len();
    }
    if needs > out.len() {
        return Err(WriteError::TooBig {
            needs,
            room: out.len(),
        });
    }
    out.fill(0xFF);
    out[..4].copy_from_slice(&MAGIC);
    out[8] = VERSION;
    out[9] = texts.len() as u8;
    out[10..12].copy_from_slice(&[0, 0]);
    out[12..16].copy_from_slice(&((needs - HEADER) as u32).to_le_bytes());
    let mut at = HEADER;
    for text in texts {
        out[at..at + 2].copy_from_slice(&(text.len() as u16).to_le_bytes());
        out[at + 2..at + 2 + text.len()].copy_from_slice(text);
        at += 2 + text.len();
    }
    let crc = crc32(&out[8..needs]);
    out[4..8].copy_from_slice(&crc.to_le_bytes());
    Ok(needs)
}

/// CRC-32 as IEEE 802.3 and zlib define it (reflected, polynomial
/// 0xEDB88320, initial and final XOR 0xFFFFFFFF), bit by bit: a region is
/// read once per boot, and a table would cost 1 KiB of the v1's flash.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in bytes {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xEDB8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}
