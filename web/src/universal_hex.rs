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
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A section of `block` holding `runs` (address, bytes), written with
    /// `data_kind` records of up to 16 bytes (not the 32 the patch writes),
    /// padded to the boundary: the input.
    fn section(out: &mut Out, block: u16, data_kind: u8, runs: &[(u32, Vec<u8>)]) {
        let start = out.len;
        let mut upper = runs.first().map_or(0, |r| r.0 >> 16);
        out.line(EXTENDED_LINEAR_ADDRESS, 0, &(upper as u16).to_be_bytes())
            .unwrap();
        let [high, low] = block.to_be_bytes();
        out.line(BLOCK_START, 0, &[high, low, 0xC0, 0xDE]).unwrap();
        for (at, bytes) in runs {
            for (i, chunk) in bytes.chunks(16).enumerate() {
                let address = at + 16 * i as u32;
                if address >> 16 != upper {
                    upper = address >> 16;
                    out.line(EXTENDED_LINEAR_ADDRESS, 0, &(upper as u16).to_be_bytes())
                        .unwrap();
                }
                out.line(data_kind, address as u16, chunk).unwrap();
            }
        }
        close(out, start).unwrap();
    }

    /// Runs of bytes: (address, bytes).
    type Runs = Vec<(u32, Vec<u8>)>;

    fn universal(sections: &[(u16, u8, Runs)]) -> Vec<u8> {
        let mut buf = vec![0; 1 << 20];
        let mut out = Out {
            buf: &mut buf,
            len: 0,
        };
        for (block, kind, runs) in sections {
            section(&mut out, *block, *kind, runs);
        }
        out.line(END_OF_FILE, 0, &[]).unwrap();
        let len = out.len;
        buf.truncate(len);
        buf
    }

    /// Each section's bytes by block type, and its data record type, read as
    /// the spec defines them (not as `patch` goes); every section starts and
    /// ends on a 512-byte boundary.
    fn separate(text: &[u8]) -> BTreeMap<u16, (u8, BTreeMap<u32, u8>)> {
        let text = std::str::from_utf8(text).unwrap();
        let mut boards: BTreeMap<u16, (u8, BTreeMap<u32, u8>)> = BTreeMap::new();
        let (mut board, mut upper, mut at) = (None, 0u32, 0usize);
        for (n, line) in text.lines().enumerate() {
            let record = parse(line.as_bytes(), n + 1).unwrap();
            let data = record.data();
            match record.kind {
                EXTENDED_LINEAR_ADDRESS => {
                    upper = u32::from(u16::from_be_bytes([data[0], data[1]])) << 16
                }
                BLOCK_START => {
                    assert_eq!((at - line_len(2)) % BLOCK, 0, "section at {at}");
                    board = Some(u16::from_be_bytes([data[0], data[1]]));
                }
                DATA | CUSTOM_DATA => {
                    let entry = boards.entry(board.unwrap()).or_default();
                    entry.0 = record.kind;
                    for (i, b) in data.iter().enumerate() {
                        let address = upper + u32::from(record.offset) + i as u32;
                        assert!(entry.1.insert(address, *b).is_none(), "{address:#x} twice");
                    }
                }
                BLOCK_END => {
                    assert_eq!(
                        (at + line.len() + 1) % BLOCK,
                        0,
                        "a section ends at line {n}"
                    );
                    board = None;
                }
                _ => {}
            }
            assert!(line.len() <= line_len(RECORD), "{line}");
            at += line.len() + 1;
        }
        boards
    }

    fn bytes(n: usize, seed: u8) -> Vec<u8> {
        (0..n)
            .map(|i| (i as u8).wrapping_mul(7).wrapping_add(seed))
            .collect()
    }

    fn flat(runs: &[(u32, Vec<u8>)]) -> BTreeMap<u32, u8> {
        runs.iter()
            .flat_map(|(at, b)| b.iter().enumerate().map(move |(i, b)| (at + i as u32, *b)))
            .collect()
    }

    #[test]
    fn the_region_lands_in_each_board_and_the_rest_stays() {
        let v1_region = 0x3_F000..0x4_0000;
        let v2_region = 0x7_B000..0x7_C000;
        // V1: code across 64 KiB, an old region's bytes from below its start
        // and up to its end, the UICR above it. V2: old region bytes across
        // its end, data after the region in its 64 KiB.
        let v1 = vec![
            (0, bytes(0x1_2345, 1)),
            (0x3_EFF0, bytes(0x30, 2)),
            (0x3_FFF8, bytes(8, 3)),
            (0x1000_1014, bytes(8, 4)),
        ];
        let v2 = vec![
            (0, bytes(0x9876, 5)),
            (0x7_BFF8, bytes(0x20, 10)),
            (0x7_C100, bytes(40, 6)),
        ];
        let other = vec![(0x100, bytes(77, 7))];
        let hex = universal(&[
            (BOARD_V1, DATA, v1.clone()),
            (0x9904, CUSTOM_DATA, other.clone()),
            (BOARD_V2, CUSTOM_DATA, v2.clone()),
        ]);
        let region = bytes(1000, 8);
        let patches = [
            Patch {
                block: BOARD_V1,
                region: v1_region.clone(),
                bytes: &region,
            },
            Patch {
                block: BOARD_V2,
                region: v2_region.clone(),
                bytes: &region,
            },
        ];
        let mut out = vec![0; 1 << 20];
        let len = patch(&hex, &patches, &mut out).unwrap();
        let boards = separate(&out[..len]);
        for (block, kind, runs, range) in [
            (BOARD_V1, DATA, &v1, v1_region),
            (BOARD_V2, CUSTOM_DATA, &v2, v2_region),
        ] {
            let mut expected = flat(runs);
            expected.retain(|at, _| !range.contains(at));
            expected.extend(flat(&[(range.start, region.clone())]));
            assert_eq!(boards[&block].0, kind, "{block:04X}'s data records");
            let got = &boards[&block].1;
            let diff: Vec<_> = expected
                .iter()
                .filter(|(at, b)| got.get(at) != Some(b))
                .map(|(at, _)| *at)
                .chain(got.keys().filter(|at| !expected.contains_key(at)).copied())
                .take(4)
                .collect();
            assert!(diff.is_empty(), "{block:04X}'s image differs at {diff:x?}");
        }
        assert!(
            boards[&0x9904].1 == flat(&other),
            "a foreign board as it was"
        );
        // Patched again (the served hex may carry a region): the new region alone.
        let again = bytes(20, 9);
        let patches = patches.map(|p| Patch { bytes: &again, ..p });
        let mut twice = vec![0; 1 << 20];
        let len2 = patch(&out[..len], &patches, &mut twice).unwrap();
        let boards = separate(&twice[..len2]);
        assert_eq!(boards[&BOARD_V2].1.get(&0x7_B000), Some(&again[0]));
        assert_eq!(boards[&BOARD_V2].1.get(&0x7_B014), None);
        assert!(std::str::from_utf8(&twice[..len2])
            .unwrap()
            .ends_with(":00000001FF\n"));
    }

    #[test]
    fn every_gap_to_a_boundary_is_filled() {
        // Region lengths move the section's end through every remainder.
        let hex = universal(&[(BOARD_V1, DATA, vec![(0, bytes(100, 1))])]);
        for n in 1..=300 {
            let region = bytes(n, 2);
            let patches = [Patch {
                block: BOARD_V1,
                region: 0x3_F000..0x4_0000,
                bytes: &region,
            }];
            let mut out = vec![0; 1 << 16];
            let len = patch(&hex, &patches, &mut out).unwrap();
            let boards = separate(&out[..len]);
            assert_eq!(boards[&BOARD_V1].1.len(), 100 + n);
        }
    }

    #[test]
    fn errors_name_the_line_and_what() {
        let hex = universal(&[(BOARD_V1, DATA, vec![(0, bytes(100, 1))])]);
        let region = [1, 2, 3];
        let v1 = Patch {
            block: BOARD_V1,
            region: 0x3_F000..0x4_0000,
            bytes: &region,
        };
        let v2 = Patch {
            block: BOARD_V2,
            ..v1.clone()
        };
        let mut out = vec![0; 1 << 16];
        let text = std::str::from_utf8(&hex).unwrap();
        let error = |text: &str, patches: &[Patch], out: &mut [u8]| {
            patch(text.as_bytes(), patches, out)
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            error(text, &[v1.clone(), v2], &mut out),
            "no section of block type 9903"
        );
        // The third line's last digit changed: its checksum no longer adds up.
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        let third = lines[2].pop().unwrap();
        lines[2].push(if third == '0' { '1' } else { '0' });
        assert_eq!(
            error(&lines.join("\n"), std::slice::from_ref(&v1), &mut out),
            "line 3: wrong checksum"
        );
        assert_eq!(
            error("hello\n", std::slice::from_ref(&v1), &mut out),
            "line 1: does not start with ':'"
        );
        assert_eq!(
            error(
                ":00000001FF\n:00000001FF\n",
                std::slice::from_ref(&v1),
                &mut out
            ),
            "line 2: a record after End Of File"
        );
        assert_eq!(
            error(":0100000042BD\n", std::slice::from_ref(&v1), &mut out),
            "line 1: a data record outside a section"
        );
        assert_eq!(
            error(
                text.trim_end_matches(":00000001FF\n"),
                std::slice::from_ref(&v1),
                &mut out
            ),
            "no End Of File record"
        );
        assert_eq!(
            error(text, &[v1], &mut out[..300]),
            "the result is over 300 bytes"
        );
    }
}
