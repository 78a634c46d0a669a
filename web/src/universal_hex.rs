//! The levels region written into a universal hex, in the browser: a pass over
//! the lines of the hex the page serves (`cargo xtask hex`'s
//! `target/hex/marble-rolling.hex`) that copies every record but the ones in
//! a board's region, adds the region's records where they belong in address
//! order, and pads each section it changed to its 512-byte boundary again.
//!
//! The format is the micro:bit Educational Foundation's "Universal Hex Format
//! Specification" 0.4.0 (`spec/index.md` of github.com/microbit-foundation/
//! spec-universal-hex), in the "512 Byte Aligned Sections" layout that
//! `xtask/src/hex.rs` writes: per board, an Extended Linear Address record at
//! a 512-byte boundary of the file, a Block Start (type `0x0A`, the board's
//! block type first), its data records (`0x00` for the V1, Custom Data `0x0D`
//! for the V2), Padded Data records (`0x0C`) and a Block End (`0x0B`) up to
//! the next boundary; one End Of File record last.
//!
//! Why here in Rust and not with the Foundation's npm library in the page: the
//! page has no bundler and `cargo web` no npm (the library would have to be
//! installed and served beside the page), while the module already holds the
//! region's writer (`game::levels_region`) and the level checks. The
//! Foundation's library reads the result in the browser test instead: an
//! independent reader, not ours checking itself. The padding is the one
//! `xtask/src/hex.rs` writes, so that the page's file for a level is the file
//! `cargo xtask hex --level` writes for it (the browser test compares the two
//! in CI, byte for byte). No allocator: the output goes to a buffer the
//! caller gives.

use core::ops::Range;

/// Record types (Intel HEX, then the spec's "Universal Hex New Record Types").
const DATA: u8 = 0x00;
const END_OF_FILE: u8 = 0x01;
const EXTENDED_SEGMENT_ADDRESS: u8 = 0x02;
const EXTENDED_LINEAR_ADDRESS: u8 = 0x04;
const BLOCK_START: u8 = 0x0A;
const BLOCK_END: u8 = 0x0B;
const PADDED_DATA: u8 = 0x0C;
const CUSTOM_DATA: u8 = 0x0D;

/// A section starts and ends on a multiple of this many bytes of the file.
const BLOCK: usize = 512;
/// Data bytes per record written (the spec's advice, the most DAPLink reads).
const RECORD: usize = 32;
/// What padding records carry (ignored by DAPLink).
const PAD: u8 = 0xFF;

/// The block type of the micro:bit V1 (nRF51822) and of the V2 (nRF52833).
pub const BOARD_V1: u16 = 0x9900;
pub const BOARD_V2: u16 = 0x9903;

/// One board's region to write: its section's block type, the flash the
/// region spans (whatever the hex has there is dropped) and its bytes, from
/// the region's start.
#[derive(Clone, Debug)]
pub struct Patch<'a> {
    pub block: u16,
    pub region: Range<u32>,
    pub bytes: &'a [u8],
}

/// Why a hex cannot be patched: `line` (from 1) of the input, or the output
/// buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexError {
    /// A line that is not a record: what is wrong with it.
    Record { line: usize, what: &'static str },
    /// A record out of its place in a universal hex.
    Misplaced { line: usize, what: &'static str },
    /// No section of this block type.
    NoSection { block: u16 },
    /// A second section of this block type (the page writes one per board).
    SecondSection { line: usize, block: u16 },
    /// No End Of File record.
    NoEnd,
    /// The result is larger than the buffer (`room` bytes).
    Full { room: usize },
}

impl core::fmt::Display for HexError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            HexError::Record { line, what } => write!(f, "line {line}: {what}"),
            HexError::Misplaced { line, what } => write!(f, "line {line}: {what}"),
            HexError::NoSection { block } => {
                write!(f, "no section of block type {block:04X}")
            }
            HexError::SecondSection { line, block } => {
                write!(f, "line {line}: a second section of block type {block:04X}")
            }
            HexError::NoEnd => f.write_str("no End Of File record"),
            HexError::Full { room } => write!(f, "the result is over {room} bytes"),
        }
    }
}

/// One record of a line.
struct Record {
    kind: u8,
    offset: u16,
    data: [u8; 255],
    len: usize,
}

impl Record {
    fn data(&self) -> &[u8] {
        &self.data[..self.len]
    }
}

fn nibble(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    }
}

/// Parses `:LLAAAATT<data>CC`, checksum checked.
fn parse(line: &[u8], number: usize) -> Result<Record, HexError> {
    let bad = |what| HexError::Record { line: number, what };
    let Some((b':', hex)) = line.split_first() else {
        return Err(bad("does not start with ':'"));
    };
    if hex.len() % 2 != 0 || hex.len() < 10 {
        return Err(bad("not a record (too short or an odd number of digits)"));
    }
    let byte = |i: usize| match (nibble(hex[2 * i]), nibble(hex[2 * i + 1])) {
        (Some(high), Some(low)) => Ok(high << 4 | low),
        _ => Err(bad("a character that is not a hex digit")),
    };
    let count = hex.len() / 2;
    let len = usize::from(byte(0)?);
    if len + 5 != count {
        return Err(bad("its byte count does not match its length"));
    }
    let mut sum = 0u8;
    for i in 0..count {
        sum = sum.wrapping_add(byte(i)?);
    }
    if sum != 0 {
        return Err(bad("wrong checksum"));
    }
    let mut record = Record {
        kind: byte(3)?,
        offset: u16::from(byte(1)?) << 8 | u16::from(byte(2)?),
        data: [0; 255],
        len,
    };
    for i in 0..len {
        record.data[i] = byte(4 + i)?;
    }
    Ok(record)
}

/// The output: lines written into a buffer.
struct Out<'o> {
    buf: &'o mut [u8],
    len: usize,
}

impl Out<'_> {
    fn push(&mut self, byte: u8) -> Result<(), HexError> {
        let room = self.buf.len();
        *self.buf.get_mut(self.len).ok_or(HexError::Full { room })? = byte;
        self.len += 1;
        Ok(())
    }

    /// One record line, `\n` at its end (the alignment counts characters).
    fn line(&mut self, kind: u8, offset: u16, data: &[u8]) -> Result<(), HexError> {
        const DIGITS: &[u8; 16] = b"0123456789ABCDEF";
        let [high, low] = offset.to_be_bytes();
        let head = [data.len() as u8, high, low, kind];
        let sum = head
            .iter()
            .chain(data)
            .fold(0u8, |sum, b| sum.wrapping_add(*b));
        self.push(b':')?;
        for &b in head.iter().chain(data).chain(&[sum.wrapping_neg()]) {
            self.push(DIGITS[usize::from(b >> 4)])?;
            self.push(DIGITS[usize::from(b & 15)])?;
        }
        self.push(b'\n')
    }
}

/// The characters a record line with `data` bytes takes, its `\n` included.
const fn line_len(data: usize) -> usize {
    12 + 2 * data
}

/// The section being copied.
struct Section<'p> {
    /// Where it starts in the output.
    start: usize,
    /// Its region, if it is a board being patched, and whether its records
    /// are written yet.
    patch: Option<&'p Patch<'p>>,
    written: bool,
    /// The data record type of its board.
    data_kind: u8,
}

/// Writes the region's records (an Extended Linear Address record first if
/// the region is in another 64 KiB than `upper`): the region is 4 KiB
/// aligned, inside one 64 KiB.
fn region(out: &mut Out, patch: &Patch, kind: u8, upper: u32) -> Result<(), HexError> {
    let high = patch.region.start >> 16;
    if high != upper >> 16 {
        out.line(EXTENDED_LINEAR_ADDRESS, 0, &(high as u16).to_be_bytes())?;
    }
    for (i, chunk) in patch.bytes.chunks(RECORD).enumerate() {
        let at = patch.region.start + (i * RECORD) as u32;
        out.line(kind, at as u16, chunk)?;
    }
    Ok(())
}

/// Padded Data and a Block End that bring the section started at `start` to
/// the next 512-byte boundary (at least a Block End's worth further), as
/// `xtask/src/hex.rs` pads.
fn close(out: &mut Out, start: usize) -> Result<(), HexError> {
    let pad = [PAD; RECORD];
    let mut left = (BLOCK - (out.len - start) % BLOCK) % BLOCK;
    if left < line_len(0) {
        left += BLOCK;
    }
    while left > line_len(RECORD) {
        let n = RECORD.min((left - 2 * line_len(0)) / 2);
        out.line(PADDED_DATA, 0, &pad[..n])?;
        left -= line_len(n);
    }
    out.line(BLOCK_END, 0, &pad[..(left - line_len(0)) / 2])
}

/// `hex` (a universal hex) with each of `patches` written into its board's
/// section, into `buf`: the length written. Sections of other block types
/// are copied as they are; each patched board must have exactly one. Two
/// patches at most (a board each); more are not written.
pub fn patch(hex: &[u8], patches: &[Patch], buf: &mut [u8]) -> Result<usize, HexError> {
    let patches = &patches[..patches.len().min(2)];
    let mut out = Out { buf, len: 0 };
    let mut upper = 0u32;
    let mut section: Option<Section> = None;
    // Where the last line, if an Extended Linear Address record outside a
    // section, starts in the output: a section's first line.
    let mut opening: Option<usize> = None;
    // Which of `patches` had their section (a board has one patch).
    let mut seen = [false; 2];
    let mut ended = false;
    for (index, raw) in hex.split(|&b| b == b'\n').enumerate() {
        let line = index + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if raw.is_empty() {
            continue;
        }
        let misplaced = |what| HexError::Misplaced { line, what };
        if ended {
            return Err(misplaced("a record after End Of File"));
        }
        let record = parse(raw, line)?;
        let data = record.data();
        let opened = opening.take();
        match record.kind {
            EXTENDED_LINEAR_ADDRESS => {
                let &[high, low] = data else {
                    return Err(misplaced(
                        "an Extended Linear Address record without 2 bytes",
                    ));
                };
                let next = u32::from(u16::from_be_bytes([high, low])) << 16;
                if let Some(open) = section.as_mut() {
                    // A region below the next 64 KiB goes before it.
                    if let Some(p) = open.patch.filter(|p| !open.written && next >= p.region.end) {
                        region(&mut out, p, open.data_kind, upper)?;
                        open.written = true;
                    }
                } else {
                    opening = Some(out.len);
                }
                out.line(EXTENDED_LINEAR_ADDRESS, 0, data)?;
                upper = next;
            }
            BLOCK_START => {
                if section.is_some() {
                    return Err(misplaced("a Block Start inside a section"));
                }
                let (Some(start), &[high, low, ..]) = (opened, data) else {
                    return Err(misplaced(
                        "a Block Start not right after an Extended Linear Address record",
                    ));
                };
                let block = u16::from_be_bytes([high, low]);
                let at = patches.iter().position(|p| p.block == block);
                if let Some(seen) = at.and_then(|at| seen.get_mut(at)) {
                    if core::mem::replace(seen, true) {
                        return Err(HexError::SecondSection { line, block });
                    }
                }
                section = Some(Section {
                    start,
                    patch: at.map(|at| &patches[at]),
                    written: false,
                    data_kind: if block == BOARD_V1 || block == BOARD_V1 + 1 {
                        DATA
                    } else {
                        CUSTOM_DATA
                    },
                });
                out.line(BLOCK_START, record.offset, data)?;
            }
            DATA | CUSTOM_DATA => {
                let Some(open) = section.as_mut() else {
                    return Err(misplaced("a data record outside a section"));
                };
                let Some(p) = open.patch else {
                    out.line(record.kind, record.offset, data)?;
                    continue;
                };
                let start = upper | u32::from(record.offset);
                let end = start + data.len() as u32;
                // The parts outside the region; the region goes before the
                // first record past it.
                let before = (p.region.start.clamp(start, end) - start) as usize;
                let after = (p.region.end.clamp(start, end) - start) as usize;
                if before > 0 {
                    out.line(record.kind, record.offset, &data[..before])?;
                }
                if after < data.len() {
                    if !open.written {
                        region(&mut out, p, open.data_kind, upper)?;
                        open.written = true;
                        if p.region.start >> 16 != upper >> 16 {
                            out.line(
                                EXTENDED_LINEAR_ADDRESS,
                                0,
                                &((upper >> 16) as u16).to_be_bytes(),
                            )?;
                        }
                    }
                    let offset = record.offset.wrapping_add(after as u16);
                    out.line(record.kind, offset, &data[after..])?;
                }
            }
            PADDED_DATA => match &section {
                Some(open) if open.patch.is_some() => {}
                Some(_) => out.line(PADDED_DATA, record.offset, data)?,
                None => return Err(misplaced("a Padded Data record outside a section")),
            },
            BLOCK_END => {
                let Some(open) = section.take() else {
                    return Err(misplaced("a Block End outside a section"));
                };
                match open.patch {
                    Some(p) => {
                        if !open.written {
                            region(&mut out, p, open.data_kind, upper)?;
                        }
                        close(&mut out, open.start)?;
                    }
                    None => out.line(BLOCK_END, record.offset, data)?,
                }
            }
            END_OF_FILE => {
                if section.is_some() {
                    return Err(misplaced("End Of File inside a section"));
                }
                out.line(END_OF_FILE, 0, &[])?;
                ended = true;
            }
            EXTENDED_SEGMENT_ADDRESS => {
                return Err(misplaced(
                    "an Extended Segment Address record (a universal hex addresses by 64 KiB)",
                ))
            }
            // Start addresses say nothing about flash.
            _ => out.line(record.kind, record.offset, data)?,
        }
    }
    if !ended {
        return Err(HexError::NoEnd);
    }
    if let Some(p) = patches.iter().zip(seen).find(|(_, seen)| !seen) {
        return Err(HexError::NoSection { block: p.0.block });
    }
    Ok(out.len)
}

#[cfg(test)]
mod tests;
