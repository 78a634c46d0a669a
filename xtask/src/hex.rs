//! The files a micro:bit owner drags onto the MICROBIT drive, made from the
//! firmware's ELF files without any tool but this crate: the flash image of an
//! ELF ([`image_of_elf`]), that image as a plain Intel HEX ([`intel_hex`]),
//! and the two boards' images in one *universal hex* ([`universal_hex`]).
//!
//! # The universal hex
//!
//! The format is the micro:bit Educational Foundation's, specified in
//! "micro:bit Universal Hex Format Specification" version 0.4.0
//! (github.com/microbit-foundation/spec-universal-hex, `spec/index.md`, also
//! published at tech.microbit.org/software/spec-universal-hex/). We write its
//! recommended "512 Byte Aligned Sections" layout: for each board a section
//! that starts at a multiple of 512 bytes of the file (DAPLink, the board's
//! interface firmware, takes the file in 512-byte USB blocks, and a block must
//! not mix two boards' data), made of an Extended Linear Address record, a
//! Block Start record (type `0x0A`) whose data begins with the block type
//! (`0x9900` micro:bit V1, `0x9903` micro:bit V2), the board's Extended Linear
//! Address and data records (standard data records `0x00` for the V1, so that
//! a V1 DAPLink that predates the format still flashes them; Custom Data
//! records `0x0D` for the V2, which every V1 DAPLink ignores), Padded Data
//! records (`0x0C`) and a Block End record (`0x0B`) that bring its end to the
//! next 512-byte boundary; one End Of File record closes the file. Records
//! carry at most 32 data bytes (the spec's advice; DAPLink reads no more) and
//! lines end in `\n` alone (the alignment counts characters).
//!
//! The wrapping is written here rather than taken from a crate: the `ihex`
//! crate's records are the six standard types and no Rust crate writes the
//! Foundation's; the Foundation's own implementation is a TypeScript package,
//! which CI runs against our file (`cargo xtask hex --check`) instead.

use std::fmt::Write as _;

use object::elf::{PT_LOAD, SHF_ALLOC, SHT_NOBITS};
use object::read::elf::{ElfFile32, ProgramHeader, SectionHeader};

/// The block type of the micro:bit V1 (nRF51822) in a Block Start record.
pub const BOARD_V1: u16 = 0x9900;
/// The block type of the micro:bit V2 (nRF52833).
pub const BOARD_V2: u16 = 0x9903;

/// Universal hex record types (spec, "Universal Hex New Record Types").
const BLOCK_START: u8 = 0x0A;
const BLOCK_END: u8 = 0x0B;
const PADDED_DATA: u8 = 0x0C;
const CUSTOM_DATA: u8 = 0x0D;
/// Standard Intel HEX record types, as the universal sections carry them.
const DATA: u8 = 0x00;
const END_OF_FILE: u8 = 0x01;
const EXTENDED_LINEAR_ADDRESS: u8 = 0x04;

/// The file is taken in blocks of this many bytes, and a section is aligned to it.
const BLOCK: usize = 512;
/// Data bytes per record: 32 in the universal hex (the spec's advice, and
/// the most DAPLink reads), 16 in the plain files (what every Intel HEX
/// reader, an old V1 DAPLink's too, has been fed for decades).
const UNIVERSAL_RECORD: usize = 32;
const PLAIN_RECORD: usize = 16;
/// The spec's example Block Start carries `C0DE` after the block type, and
/// the Foundation's library rejects a Block Start with other than 4 data bytes.
const BLOCK_START_TAIL: [u8; 2] = [0xC0, 0xDE];
/// What padding records carry (ignored by DAPLink; erased flash reads 0xFF).
const PAD: u8 = 0xFF;

/// Bytes to write to flash, by address: disjoint runs in address order,
/// adjacent runs joined.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Image {
    runs: Vec<(u32, Vec<u8>)>,
}

impl Image {
    /// Adds `bytes` at `address`; an overlap with what is there is an error.
    pub fn add(&mut self, address: u32, bytes: &[u8]) -> Result<(), String> {
        if bytes.is_empty() {
            return Ok(());
        }
        let end = u64::from(address) + bytes.len() as u64;
        if end > 1 << 32 {
            return Err(format!(
                "{} bytes at {address:#010x} run past the 32-bit address space",
                bytes.len()
            ));
        }
        let at = self.runs.partition_point(|(start, _)| *start < address);
        let overlaps_before = at > 0 && {
            let (start, run) = &self.runs[at - 1];
            u64::from(*start) + run.len() as u64 > u64::from(address)
        };
        let overlaps_after = self
            .runs
            .get(at)
            .is_some_and(|(start, _)| u64::from(*start) < end);
        if overlaps_before || overlaps_after {
            return Err(format!(
                "{} bytes at {address:#010x} overlap bytes already in the image",
                bytes.len()
            ));
        }
        self.runs.insert(at, (address, bytes.to_vec()));
        // Join with the neighbours that touch it.
        if at + 1 < self.runs.len() && u64::from(self.runs[at + 1].0) == end {
            let (_, next) = self.runs.remove(at + 1);
            self.runs[at].1.extend_from_slice(&next);
        }
        if at > 0 {
            let (start, run) = &self.runs[at - 1];
            if u64::from(*start) + run.len() as u64 == u64::from(address) {
                let (_, this) = self.runs.remove(at);
                self.runs[at - 1].1.extend_from_slice(&this);
            }
        }
        Ok(())
    }

    /// The runs: `(address, bytes)`, in address order, none touching another.
    pub fn runs(&self) -> &[(u32, Vec<u8>)] {
        &self.runs
    }

    /// The number of bytes to write.
    pub fn len(&self) -> usize {
        self.runs.iter().map(|(_, run)| run.len()).sum()
    }

    /// Whether there is nothing to write.
    pub fn is_empty(&self) -> bool {
        self.runs.is_empty()
    }

    /// From the lowest address to the highest, gaps filled with zeros: what
    /// `objcopy -O binary` writes, and the lowest address.
    pub fn flat(&self) -> (u32, Vec<u8>) {
        let Some(((first, _), (last, last_run))) = self.runs.first().zip(self.runs.last()) else {
            return (0, Vec::new());
        };
        let mut flat = vec![0; (*last - *first) as usize + last_run.len()];
        for (start, run) in &self.runs {
            let at = (*start - *first) as usize;
            flat[at..at + run.len()].copy_from_slice(run);
        }
        (*first, flat)
    }
}

/// A loadable program header of an ELF file, as far as the image needs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Segment {
    pub offset: u64,
    pub vaddr: u64,
    /// Where the loader puts it (flash for initialised RAM data).
    pub paddr: u64,
    pub filesz: u64,
}

/// An allocated section with contents in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Section<'a> {
    pub name: &'a str,
    pub offset: u64,
    pub data: &'a [u8],
}

/// Where `section` goes in flash: its place in the loadable segment whose
/// file bytes hold it, moved to that segment's physical address, as objcopy
/// computes a section's load address (so `.data`, linked to run in RAM,
/// lands in flash behind the code, where the start-up code copies it from).
pub fn load_address(section: &Section, segments: &[Segment]) -> Result<u32, String> {
    let size = section.data.len() as u64;
    let segment = segments
        .iter()
        .find(|s| section.offset >= s.offset && section.offset + size <= s.offset + s.filesz)
        .ok_or_else(|| {
            format!(
                "section {} ({size} bytes at file offset {:#x}) is in no loadable segment",
                section.name, section.offset
            )
        })?;
    let address = segment.paddr + (section.offset - segment.offset);
    u32::try_from(address).map_err(|_| {
        format!(
            "section {} loads at {address:#x}, beyond 32 bits",
            section.name
        )
    })
}

/// The image of `sections` placed by `segments` (see [`load_address`]).
pub fn image_of(sections: &[Section], segments: &[Segment]) -> Result<Image, String> {
    let mut image = Image::default();
    for section in sections {
        let address = load_address(section, segments)?;
        image
            .add(address, section.data)
            .map_err(|e| format!("section {}: {e}", section.name))?;
    }
    Ok(image)
}

/// The flash image of a 32-bit ELF file: its allocated sections with
/// contents (not `.bss`, not the debug and defmt sections), at their load
/// addresses.
pub fn image_of_elf(elf: &[u8]) -> Result<Image, String> {
    let file = ElfFile32::<object::Endianness>::parse(elf)
        .map_err(|e| format!("not a 32-bit ELF file: {e}"))?;
    let endian = file.endian();
    let segments: Vec<Segment> = file
        .elf_program_headers()
        .iter()
        .filter(|ph| ph.p_type(endian) == PT_LOAD)
        .map(|ph| Segment {
            offset: ph.p_offset(endian).into(),
            vaddr: ph.p_vaddr(endian).into(),
            paddr: ph.p_paddr(endian).into(),
            filesz: ph.p_filesz(endian).into(),
        })
        .collect();
    let table = file.elf_section_table();
    let mut sections = Vec::new();
    for header in table.iter() {
        let flags = header.sh_flags(endian);
        if flags & SHF_ALLOC == 0 || header.sh_type(endian) == SHT_NOBITS {
            continue;
        }
        let name = table
            .section_name(endian, header)
            .ok()
            .and_then(|name| std::str::from_utf8(name).ok())
            .unwrap_or("(unnamed)");
        let data = header
            .data(endian, elf)
            .map_err(|e| format!("section {name}: cannot read its bytes: {e}"))?;
        if data.is_empty() {
            continue;
        }
        sections.push(Section {
            name,
            offset: header.sh_offset(endian).into(),
            data,
        });
    }
    image_of(&sections, &segments)
}

/// The image as data and Extended Linear Address records of at most `width`
/// bytes, none crossing a 64 KiB boundary, an Extended Linear Address record
/// first (explicit even at 0: the spec wants one at the head of a section).
fn records(image: &Image, width: usize) -> Vec<ihex::Record> {
    let mut records = Vec::new();
    let mut upper = None;
    for (start, run) in image.runs() {
        let mut address = *start;
        let mut rest = run.as_slice();
        while !rest.is_empty() {
            let high = (address >> 16) as u16;
            if upper != Some(high) {
                records.push(ihex::Record::ExtendedLinearAddress(high));
                upper = Some(high);
            }
            let to_boundary = 0x1_0000 - (address & 0xFFFF) as usize;
            let take = rest.len().min(width).min(to_boundary);
            records.push(ihex::Record::Data {
                offset: address as u16,
                value: rest[..take].to_vec(),
            });
            rest = &rest[take..];
            address = address.wrapping_add(take as u32);
        }
    }
    records
}

/// The image as a plain Intel HEX file (16-byte records), as a V1 whose
/// DAPLink predates universal hexes needs it.
pub fn intel_hex(image: &Image) -> Result<String, String> {
    let mut all = records(image, PLAIN_RECORD);
    all.push(ihex::Record::EndOfFile);
    ihex::create_object_file_representation(&all)
        .map_err(|e| format!("cannot write the Intel HEX records: {e:?}"))
}

/// What a plain Intel HEX file writes to flash: its data records, placed by
/// its Extended Linear and Extended Segment Address records, up to its End
/// Of File (start address records say nothing about flash).
pub fn image_of_intel_hex(text: &str) -> Result<Image, String> {
    let mut image = Image::default();
    let mut base = 0u32;
    for (number, record) in ihex::Reader::new(text).enumerate() {
        let line = number + 1;
        match record.map_err(|e| format!("record {line}: {e}"))? {
            ihex::Record::Data { offset, value } => image
                .add(base.wrapping_add(u32::from(offset)), &value)
                .map_err(|e| format!("record {line}: {e}"))?,
            ihex::Record::ExtendedLinearAddress(upper) => base = u32::from(upper) << 16,
            ihex::Record::ExtendedSegmentAddress(segment) => base = u32::from(segment) << 4,
            ihex::Record::EndOfFile => return Ok(image),
            ihex::Record::StartLinearAddress(_) | ihex::Record::StartSegmentAddress { .. } => {}
        }
    }
    Err("no End Of File record".into())
}

/// One record line (`\n` included) of any type, the universal ones too.
fn line(kind: u8, offset: u16, data: &[u8]) -> String {
    let mut bytes = vec![data.len() as u8, (offset >> 8) as u8, offset as u8, kind];
    bytes.extend_from_slice(data);
    let checksum = ihex::checksum(&bytes);
    bytes.push(checksum);
    let mut text = String::with_capacity(2 + 2 * bytes.len());
    text.push(':');
    for byte in bytes {
        let _ = write!(text, "{byte:02X}");
    }
    text.push('\n');
    text
}

/// The characters a record line with `data` bytes takes (`:`, count, address,
/// type, data, checksum, `\n`).
const fn line_len(data: usize) -> usize {
    12 + 2 * data
}

/// Appends `board`'s section (see the module doc) to `out`, which must end
/// on a block boundary.
fn section(out: &mut String, board: u16, image: &Image) {
    debug_assert_eq!(out.len() % BLOCK, 0, "a section starts on a block boundary");
    let start = out.len();
    let data_kind = if board == BOARD_V1 { DATA } else { CUSTOM_DATA };
    let mut records = records(image, UNIVERSAL_RECORD).into_iter();
    // `records` opens with the Extended Linear Address record the section
    // starts with; the Block Start follows it.
    let first_upper = match records.next() {
        Some(ihex::Record::ExtendedLinearAddress(upper)) => upper,
        _ => 0,
    };
    out.push_str(&line(
        EXTENDED_LINEAR_ADDRESS,
        0,
        &first_upper.to_be_bytes(),
    ));
    let [high, low] = board.to_be_bytes();
    out.push_str(&line(
        BLOCK_START,
        0,
        &[high, low, BLOCK_START_TAIL[0], BLOCK_START_TAIL[1]],
    ));
    for record in records {
        match record {
            ihex::Record::Data { offset, value } => out.push_str(&line(data_kind, offset, &value)),
            ihex::Record::ExtendedLinearAddress(upper) => {
                out.push_str(&line(EXTENDED_LINEAR_ADDRESS, 0, &upper.to_be_bytes()))
            }
            _ => {}
        }
    }
    // What is left to the boundary, with room for the Block End at least.
    let mut left = (BLOCK - (out.len() - start) % BLOCK) % BLOCK;
    if left < line_len(0) {
        left += BLOCK;
    }
    let largest_end = line_len(UNIVERSAL_RECORD);
    while left > largest_end {
        // Leave at least an empty Block End's worth.
        let pad = UNIVERSAL_RECORD.min((left - 2 * line_len(0)) / 2);
        out.push_str(&line(PADDED_DATA, 0, &vec![PAD; pad]));
        left -= line_len(pad);
    }
    out.push_str(&line(BLOCK_END, 0, &vec![PAD; (left - line_len(0)) / 2]));
    debug_assert_eq!(out.len() % BLOCK, 0, "a section ends on a block boundary");
}

/// The universal hex of the V1 and V2 images: the V1's section first (the
/// spec's advice: a V1 DAPLink older than 0255 halts the target only when it
/// first writes), then the V2's, then End Of File.
pub fn universal_hex(v1: &Image, v2: &Image) -> String {
    let mut out = String::new();
    section(&mut out, BOARD_V1, v1);
    section(&mut out, BOARD_V2, v2);
    out.push_str(&line(END_OF_FILE, 0, &[]));
    out
}

#[cfg(test)]
mod tests;
