//! `cargo xtask size-report`: the micro:bit v2 firmware's flash and static-RAM
//! budget, as a markdown table on stdout. Exit 1 when over a budget, 2 on a
//! usage or tooling error.
//!
//!   Flash      = text + data   (vector table, code, read-only data, and the
//!                               initial values of .data, all stored in flash)
//!   Static RAM = data + bss    (.data, .bss and .uninit: the defmt-RTT buffer,
//!                               embassy task arenas, statics; not the stack,
//!                               which takes the rest of RAM)
//!
//! Measured from the ELF's section headers with the `object` crate, with the
//! Berkeley accounting of `llvm-size -B` (so no llvm-tools component is needed
//! and the figures are the ones `llvm-size -B` prints). Budgets in bytes, the
//! board's ([`crate::boards::MICROBIT`]'s): FLASH_BUDGET (default 147456 = 144
//! KiB), RAM_BUDGET (default 16384 = 16 KiB),
//! issue 27's: the v2 runs event stepping, about 18 KiB more code than fixed steps.
//!
//! It also prints the stepping the firmware links, read from the ELF: the byte
//! of the firmware's [`STEPPING_SYMBOL`], which the same constant that picks the
//! game's stepper sets. The micro:bit firmware must link events (no board ships
//! fixed steps, issue 27): fixed is a failure like a budget overrun.

use std::path::{Path, PathBuf};

use object::elf::{SHF_ALLOC, SHF_EXECINSTR, SHF_WRITE, SHT_NOBITS};
use object::read::elf::{FileHeader, SectionHeader};
use object::{elf, Endianness, FileKind, Object, ObjectSection, ObjectSymbol};

use crate::boards::Board;
use crate::error::{say, Failure, Outcome};

/// What the accounting needs of a section header.
#[derive(Clone, Copy, Debug)]
pub struct Section {
    pub sh_type: u32,
    pub sh_flags: u64,
    pub size: u64,
}

/// Berkeley totals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Berkeley {
    pub text: u64,
    pub data: u64,
    pub bss: u64,
}

impl Berkeley {
    pub fn flash(&self) -> u64 {
        self.text + self.data
    }

    pub fn ram(&self) -> u64 {
        self.data + self.bss
    }
}

/// llvm-size's Berkeley rules (`ELFObjectFile::isBerkeleyText`/`isBerkeleyData`,
/// `isSectionBSS`), in its order. Text: allocated and executable or read-only
/// (so .vector_table and .rodata count); data: allocated, loaded, not text;
/// bss: not loaded (NOBITS), allocated or writable. Non-allocated sections
/// (.defmt, debug info, symbols) count nowhere.
pub fn berkeley(sections: &[Section]) -> Berkeley {
    let mut totals = Berkeley::default();
    for section in sections {
        let flags = section.sh_flags;
        let alloc = flags & u64::from(SHF_ALLOC) != 0;
        let write = flags & u64::from(SHF_WRITE) != 0;
        let exec = flags & u64::from(SHF_EXECINSTR) != 0;
        let nobits = section.sh_type == SHT_NOBITS;
        if alloc && (exec || !write) {
            totals.text += section.size;
        } else if alloc && !nobits {
            totals.data += section.size;
        } else if (alloc || write) && nobits {
            totals.bss += section.size;
        }
    }
    totals
}

/// The section headers of an ELF file (32- or 64-bit, either byte order).
pub fn sections(data: &[u8]) -> Result<Vec<Section>, String> {
    match FileKind::parse(data).map_err(|e| e.to_string())? {
        FileKind::Elf32 => sections_of::<elf::FileHeader32<Endianness>>(data),
        FileKind::Elf64 => sections_of::<elf::FileHeader64<Endianness>>(data),
        kind => Err(format!("not an ELF file ({kind:?})")),
    }
}

fn sections_of<H: FileHeader<Endian = Endianness>>(data: &[u8]) -> Result<Vec<Section>, String> {
    let header = H::parse(data).map_err(|e| e.to_string())?;
    let endian = header.endian().map_err(|e| e.to_string())?;
    let table = header.sections(endian, data).map_err(|e| e.to_string())?;
    Ok(table
        .iter()
        .map(|section| Section {
            sh_type: section.sh_type(endian),
            sh_flags: section.sh_flags(endian).into(),
            size: section.sh_size(endian).into(),
        })
        .collect())
}

/// The symbol whose one byte says the firmware's stepping (1 events, 0 fixed):
/// `boards/microbit/src/main.rs`.
pub const STEPPING_SYMBOL: &str = "MARBLE_STEPPING_EVENTS";

/// The physics stepper a firmware links.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stepping {
    Events,
    Fixed,
}

impl Stepping {
    pub fn name(self) -> &'static str {
        match self {
            Stepping::Events => "events",
            Stepping::Fixed => "fixed",
        }
    }
}

/// The stepping named by [`STEPPING_SYMBOL`] in an ELF: `Ok(None)` when the
/// ELF has no such symbol (not our firmware, or an older one), an error when
/// the symbol is there but not one byte of 0 or 1 in a section with contents.
pub fn stepping(data: &[u8]) -> Result<Option<Stepping>, String> {
    let file = object::File::parse(data).map_err(|e| e.to_string())?;
    let Some(symbol) = file.symbols().find(|s| s.name() == Ok(STEPPING_SYMBOL)) else {
        return Ok(None);
    };
    if symbol.size() != 1 {
        return Err(format!(
            "{STEPPING_SYMBOL} is {} bytes, not 1",
            symbol.size()
        ));
    }
    let section = symbol
        .section_index()
        .and_then(|index| file.section_by_index(index).ok())
        .ok_or_else(|| format!("{STEPPING_SYMBOL} is in no section"))?;
    let bytes = section
        .data_range(symbol.address(), 1)
        .map_err(|e| e.to_string())?
        .ok_or_else(|| format!("{STEPPING_SYMBOL} lies outside its section's contents"))?;
    match bytes {
        [0] => Ok(Some(Stepping::Fixed)),
        [1] => Ok(Some(Stepping::Events)),
        other => Err(format!("{STEPPING_SYMBOL} holds {other:?}, not 0 or 1")),
    }
}

fn unreadable(path: &Path, e: impl std::fmt::Display) -> Failure {
    Failure::new(format!("cannot read {}: {e}", path.display())).status(2)
}

/// Measures the ELF at `path`.
pub fn measure(path: &Path) -> Result<Berkeley, Failure> {
    let data = std::fs::read(path).map_err(|e| unreadable(path, e))?;
    let sections = sections(&data).map_err(|e| unreadable(path, e))?;
    Ok(berkeley(&sections))
}

/// The stepping the ELF at `path` names ([`stepping`]).
pub fn stepping_of(path: &Path) -> Result<Option<Stepping>, Failure> {
    let data = std::fs::read(path).map_err(|e| unreadable(path, e))?;
    stepping(&data).map_err(|e| unreadable(path, e))
}

fn kib(bytes: u64) -> String {
    format!("{:.1} KiB", bytes as f64 / 1024.0)
}

fn share(used: u64, budget: u64) -> String {
    format!("{:.0} %", 100.0 * used as f64 / budget as f64)
}

fn verdict(used: u64, budget: u64) -> &'static str {
    if used <= budget {
        "ok"
    } else {
        "**OVER**"
    }
}

/// The markdown report on `board`'s firmware.
pub fn table(board: &str, size: &Berkeley, flash_budget: u64, ram_budget: u64) -> String {
    let line = |what: &str, used: u64, budget: u64| {
        format!(
            "| {what} | {used} B ({}) | {} | {} | {} |",
            kib(used),
            kib(budget),
            share(used, budget),
            verdict(used, budget)
        )
    };
    [
        format!("| {board} firmware | used | budget | share | |"),
        "| --- | ---: | ---: | ---: | --- |".to_string(),
        line("Flash (text + data)", size.flash(), flash_budget),
        line("Static RAM (data + bss)", size.ram(), ram_budget),
    ]
    .join("\n")
}

/// `cargo xtask size-report [--no-build] [ELF]` on `board` (the micro:bit
/// v2): an explicit ELF is measured as it is, against the board's budgets;
/// otherwise its firmware, built first unless `--no-build`.
pub fn run(board: &Board, no_build: bool, elf: Option<PathBuf>) -> Outcome {
    let flash_budget = board.budget(&board.budgets.flash)?;
    let ram_budget = board.budget(&board.budgets.ram)?;
    let explicit = elf.is_some();
    let elf = match elf {
        Some(elf) => elf,
        None if no_build => board.game.built()?,
        None => board.game.build()?,
    };
    if !elf.is_file() {
        return Err(Failure::new(format!(
            "{} not found (build it, or drop --no-build)",
            elf.display()
        ))
        .status(2));
    }
    let size = measure(&elf)?;
    let stepping = stepping_of(&elf)?;
    println!("{}", table(board.name, &size, flash_budget, ram_budget));
    let mut status = 0;
    match stepping {
        Some(stepping) => println!("stepping: {} ({STEPPING_SYMBOL})", stepping.name()),
        None => println!("stepping: unknown (no {STEPPING_SYMBOL} symbol)"),
    }
    match (stepping, explicit) {
        (Some(Stepping::Events), _) | (None, true) => {}
        (Some(Stepping::Fixed), _) => {
            say!("the firmware links fixed steps: every board runs event stepping (issue 27)");
            status = 1;
        }
        (None, false) => {
            say!(
                "the {} firmware has no {STEPPING_SYMBOL} symbol",
                board.name
            );
            status = 1;
        }
    }
    if size.flash() > flash_budget {
        say!(
            "flash {} B exceeds the budget of {flash_budget} B",
            size.flash()
        );
        status = 1;
    }
    if size.ram() > ram_budget {
        say!(
            "static RAM {} B exceeds the budget of {ram_budget} B",
            size.ram()
        );
        status = 1;
    }
    Ok(status)
}

#[cfg(test)]
mod tests {
    use super::*;
    use object::elf::{SHT_ARM_ATTRIBUTES, SHT_PROGBITS, SHT_SYMTAB};

    const A: u64 = SHF_ALLOC as u64;
    const W: u64 = SHF_WRITE as u64;
    const X: u64 = SHF_EXECINSTR as u64;

    fn s(sh_type: u32, sh_flags: u64, size: u64) -> Section {
        Section {
            sh_type,
            sh_flags,
            size,
        }
    }

    #[test]
    fn berkeley_accounting() {
        let sections = [
            s(0, 0, 0),                     // null section
            s(SHT_PROGBITS, A, 0x400),      // .vector_table
            s(SHT_PROGBITS, A | X, 50_000), // .text
            s(SHT_PROGBITS, A, 6_000),      // .rodata
            s(SHT_PROGBITS, A | W, 60),     // .data
            s(SHT_NOBITS, A | W, 4_000),    // .bss
            s(SHT_NOBITS, A | W, 700),      // .uninit
            s(SHT_PROGBITS, 0, 9_999),      // .defmt
            s(SHT_PROGBITS, 0x30, 123_456), // .debug_str (merge, strings)
            s(SHT_SYMTAB, 0, 77_777),       // .symtab
            s(SHT_ARM_ATTRIBUTES, 0, 50),   // .ARM.attributes
            s(SHT_PROGBITS, A | W | X, 8),  // writable code: text, as llvm-size has it
            s(SHT_NOBITS, A, 16),           // read-only NOBITS: text, as llvm-size has it
            s(SHT_NOBITS, W, 32),           // writable, not allocated: bss
        ];
        let size = berkeley(&sections);
        assert_eq!(
            size,
            Berkeley {
                text: 0x400 + 50_000 + 6_000 + 8 + 16,
                data: 60,
                bss: 4_732
            }
        );
        assert_eq!(size.flash(), size.text + 60);
        assert_eq!(size.ram(), 60 + 4_732);
    }

    #[test]
    fn report_table() {
        let size = Berkeley {
            text: 56_000,
            data: 1_060,
            bss: 3_792,
        };
        assert_eq!(
            table("micro:bit v2", &size, 65536, 16384),
            "| micro:bit v2 firmware | used | budget | share | |\n\
             | --- | ---: | ---: | ---: | --- |\n\
             | Flash (text + data) | 57060 B (55.7 KiB) | 64.0 KiB | 87 % | ok |\n\
             | Static RAM (data + bss) | 4852 B (4.7 KiB) | 16.0 KiB | 30 % | ok |"
        );
        assert!(table("micro:bit v2", &size, 1000, 16384).contains("| 5706 % | **OVER** |"));
    }

    /// A little-endian ARM ELF with `name` as a data object of `bytes` in
    /// `.rodata`, built with `object`'s writer.
    fn elf_with(name: &str, bytes: &[u8]) -> Vec<u8> {
        use object::write::{Object as Writer, Symbol, SymbolSection};
        use object::{
            Architecture, BinaryFormat, SectionKind, SymbolFlags, SymbolKind, SymbolScope,
        };
        let mut elf = Writer::new(BinaryFormat::Elf, Architecture::Arm, Endianness::Little);
        let rodata = elf.add_section(Vec::new(), b".rodata".to_vec(), SectionKind::ReadOnlyData);
        // Something before the symbol, so its offset in the section matters.
        elf.append_section_data(rodata, &[0xAA; 7], 1);
        let offset = elf.append_section_data(rodata, bytes, 1);
        elf.add_symbol(Symbol {
            name: name.as_bytes().to_vec(),
            value: offset,
            size: bytes.len() as u64,
            kind: SymbolKind::Data,
            scope: SymbolScope::Linkage,
            weak: false,
            section: SymbolSection::Section(rodata),
            flags: SymbolFlags::None,
        });
        elf.write().expect("an ELF in memory")
    }

    #[test]
    fn reads_the_stepping_symbol() {
        assert_eq!(
            stepping(&elf_with(STEPPING_SYMBOL, &[1])),
            Ok(Some(Stepping::Events))
        );
        assert_eq!(
            stepping(&elf_with(STEPPING_SYMBOL, &[0])),
            Ok(Some(Stepping::Fixed))
        );
        assert_eq!(stepping(&elf_with("SOMETHING_ELSE", &[1])), Ok(None));
        let bad = stepping(&elf_with(STEPPING_SYMBOL, &[2])).unwrap_err();
        assert!(bad.contains("not 0 or 1"), "{bad}");
        let wide = stepping(&elf_with(STEPPING_SYMBOL, &[1, 0])).unwrap_err();
        assert!(wide.contains("2 bytes"), "{wide}");
        assert!(stepping(b"not an ELF").is_err());
    }

    #[test]
    fn rejects_what_is_not_elf() {
        assert!(sections(b"not an ELF file at all").is_err());
        assert!(sections(&[]).is_err());
    }

    #[test]
    fn measures_a_real_elf() {
        // This test binary itself: every count must be consistent with its headers.
        let Ok(exe) = std::env::current_exe() else {
            return;
        };
        let Ok(data) = std::fs::read(exe) else { return };
        if let Ok(sections) = sections(&data) {
            let size = berkeley(&sections);
            assert!(size.text > 0);
        }
    }
}
