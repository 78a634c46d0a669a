//! The firmware's code symbols, for attributing program counters to functions:
//! the symbols `llvm-nm` types `t`, `T`, `w` or `W` (code, and weak symbols that
//! are not objects), read with the `object` crate instead, and their names
//! demangled with `rustc-demangle`.

use std::collections::HashMap;

use object::elf::{
    EM_ARM, SHF_EXECINSTR, SHN_ABS, SHN_COMMON, SHN_UNDEF, SHT_SYMTAB, STB_GLOBAL, STB_LOCAL,
    STB_WEAK, STT_COMMON, STT_FILE, STT_OBJECT, STT_SECTION,
};
use object::read::elf::{FileHeader, SectionHeader, Sym};
use object::{elf, Endianness, FileKind, SymbolIndex};

/// One symbol as llvm-nm lists it: address (Thumb bit cleared), size, and its
/// mangled name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Symbol {
    pub address: u64,
    pub size: u64,
    pub mangled: String,
}

/// The code symbols of an ELF file.
pub fn code_symbols(data: &[u8]) -> Result<Vec<Symbol>, String> {
    match FileKind::parse(data).map_err(|e| e.to_string())? {
        FileKind::Elf32 => symbols_of::<elf::FileHeader32<Endianness>>(data),
        FileKind::Elf64 => symbols_of::<elf::FileHeader64<Endianness>>(data),
        kind => Err(format!("not an ELF file ({kind:?})")),
    }
}

fn symbols_of<H: FileHeader<Endian = Endianness>>(data: &[u8]) -> Result<Vec<Symbol>, String> {
    let header = H::parse(data).map_err(|e| e.to_string())?;
    let endian = header.endian().map_err(|e| e.to_string())?;
    let sections = header.sections(endian, data).map_err(|e| e.to_string())?;
    let table = sections
        .symbols(endian, data, SHT_SYMTAB)
        .map_err(|e| e.to_string())?;
    let arm = header.e_machine(endian) == EM_ARM;
    let mut symbols = Vec::new();
    for (index, sym) in table.iter().enumerate().skip(1) {
        let name = table.symbol_name(endian, sym).unwrap_or_default();
        let name = String::from_utf8_lossy(name);
        let (kind, bind, shndx) = (sym.st_type(), sym.st_bind(), sym.st_shndx(endian));
        // llvm-nm skips what LLVM calls format-specific symbols: file and section
        // symbols and, on ARM, unnamed ones and the $a/$t/$d mapping symbols.
        if kind == STT_FILE || kind == STT_SECTION {
            continue;
        }
        if arm && (name.is_empty() || ["$a", "$t", "$d"].iter().any(|m| name.starts_with(m))) {
            continue;
        }
        let listed = if bind == STB_WEAK {
            // `w`/`W`, wherever they are, unless objects (`v`/`V`).
            kind != STT_OBJECT
        } else if [SHN_UNDEF, SHN_COMMON, SHN_ABS].contains(&shndx)
            || kind == STT_COMMON
            || (bind != STB_GLOBAL && bind != STB_LOCAL)
        {
            // `U`, `C`, `a`, or a binding llvm-nm does not type as code.
            false
        } else {
            // `t`/`T`: in an executable section.
            table
                .symbol_section(endian, sym, SymbolIndex(index))
                .ok()
                .flatten()
                .and_then(|section| sections.section(section).ok())
                .is_some_and(|section| {
                    let flags: u64 = section.sh_flags(endian).into();
                    flags & u64::from(SHF_EXECINSTR) != 0
                })
        };
        if listed {
            symbols.push(Symbol {
                address: sym.st_value(endian).into() & !1,
                size: sym.st_size(endian).into(),
                mangled: name.into_owned(),
            });
        }
    }
    Ok(symbols)
}

/// The name as `llvm-nm -C` spells it, which orders symbols that share an
/// address and a size: LLVM demangles Rust's legacy symbols as Itanium ones
/// (path segments joined, escapes and hash kept) and v0 symbols in full.
pub fn nm_name(mangled: &str) -> String {
    if let Some(path) = itanium_path(mangled) {
        return path;
    }
    match rustc_demangle::try_demangle(mangled) {
        Ok(demangled) => demangled.to_string(),
        Err(_) => mangled.to_string(),
    }
}

/// `_ZN<len><ident>...E` as `ident::ident`, when it is that simple.
fn itanium_path(mangled: &str) -> Option<String> {
    let mut rest = mangled.strip_prefix("_ZN")?;
    let mut parts = Vec::new();
    while !rest.starts_with('E') {
        let digits = rest.len() - rest.trim_start_matches(|c: char| c.is_ascii_digit()).len();
        let len: usize = rest[..digits].parse().ok()?;
        let ident = rest.get(digits..digits + len)?;
        parts.push(ident);
        rest = &rest[digits + len..];
    }
    (rest == "E").then(|| parts.join("::"))
}

/// A function's name for the tables: demangled without the hash, and typenum's
/// nested type-level numbers (`<typenum::…>` inside another `<…>`) cut to
/// `<..>`.
pub fn readable(mangled: &str) -> String {
    let name = match rustc_demangle::try_demangle(mangled) {
        Ok(demangled) => format!("{demangled:#}"),
        Err(_) => mangled.to_string(),
    };
    shorten_typenum(&name)
}

/// Python's `re.sub(r'<typenum::.*?>(?=>)', '<..>', name)`: from `<typenum::`
/// to the first `>` that is followed by another `>`.
pub fn shorten_typenum(name: &str) -> String {
    const OPEN: &str = "<typenum::";
    let mut out = String::with_capacity(name.len());
    let mut rest = name;
    while let Some(at) = rest.find(OPEN) {
        let after = &rest[at + OPEN.len()..];
        let Some(close) = after.find(">>") else { break };
        out.push_str(&rest[..at]);
        out.push_str("<..>");
        rest = &after[close + 1..];
    }
    out.push_str(rest);
    out
}

/// Program counter → function name: the last symbol (by address, size,
/// llvm-nm name) starting at or below the pc, if the pc is within its size
/// (at least 2 bytes: one Thumb instruction).
pub struct Symbols {
    /// (address, size, name id), sorted.
    entries: Vec<(u64, u64, usize)>,
    names: Vec<String>,
    ids: HashMap<String, usize>,
    cache: HashMap<u64, usize>,
}

impl Symbols {
    pub fn new(symbols: &[Symbol]) -> Self {
        let mut keyed: Vec<(u64, u64, String, String)> = symbols
            .iter()
            .map(|s| (s.address, s.size, nm_name(&s.mangled), readable(&s.mangled)))
            .collect();
        keyed.sort();
        let mut table = Symbols {
            entries: Vec::with_capacity(keyed.len()),
            names: Vec::new(),
            ids: HashMap::new(),
            cache: HashMap::new(),
        };
        for (address, size, _, name) in keyed {
            let id = table.intern(name);
            table.entries.push((address, size, id));
        }
        table
    }

    fn intern(&mut self, name: String) -> usize {
        if let Some(&id) = self.ids.get(&name) {
            return id;
        }
        self.names.push(name.clone());
        self.ids.insert(name, self.names.len() - 1);
        self.names.len() - 1
    }

    /// The id of the function holding `pc` (`?<hex>` when none does); equal
    /// names have equal ids.
    pub fn id(&mut self, pc: u64) -> usize {
        if let Some(&id) = self.cache.get(&pc) {
            return id;
        }
        let found = self.entries.partition_point(|&(address, ..)| address <= pc);
        let id = match found.checked_sub(1).map(|i| self.entries[i]) {
            Some((address, size, id)) if pc < address + size.max(2) => id,
            _ => self.intern(format!("?{pc:x}")),
        };
        self.cache.insert(pc, id);
        id
    }

    pub fn name(&self, id: usize) -> &str {
        &self.names[id]
    }

    /// The entry addresses of every function named `…::name` (each of a
    /// generic function's instances).
    pub fn entries_of(&self, name: &str) -> Vec<u64> {
        let tail = format!("::{name}");
        self.entries
            .iter()
            .filter(|&&(_, _, id)| self.names[id].ends_with(&tail))
            .map(|&(address, ..)| address & !1)
            .collect()
    }

    /// The address range of the lowest-addressed symbol whose name is `path`
    /// or inside it (`path::…`).
    pub fn range_of(&self, path: &str) -> Option<(u64, u64)> {
        let inside = format!("{path}::");
        self.entries
            .iter()
            .find(|&&(_, _, id)| self.names[id] == path || self.names[id].starts_with(&inside))
            .map(|&(address, size, _)| (address, address + size))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn symbol(address: u64, size: u64, mangled: &str) -> Symbol {
        Symbol {
            address,
            size,
            mangled: mangled.into(),
        }
    }

    #[test]
    fn legacy_names() {
        let mangled = "_ZN4core3fmt5write17h0123456789abcdefE";
        assert_eq!(nm_name(mangled), "core::fmt::write::h0123456789abcdef");
        assert_eq!(readable(mangled), "core::fmt::write");
        let generic = "_ZN60_$LT$core..cell..BorrowError$u20$as$u20$core..fmt..Debug$GT$3fmt17h1111111111111111E";
        assert_eq!(
            readable(generic),
            "<core::cell::BorrowError as core::fmt::Debug>::fmt"
        );
        assert_eq!(readable("memcpy"), "memcpy");
        assert_eq!(nm_name("__aeabi_uldivmod"), "__aeabi_uldivmod");
    }

    #[test]
    fn typenum_is_shortened() {
        assert_eq!(
            shorten_typenum("fixed::FixedI32<typenum::uint::UInt<typenum::B1>>::mul"),
            "fixed::FixedI32<..>>::mul"
        );
        assert_eq!(shorten_typenum("a<typenum::X>b<typenum::Y>>"), "a<..>>");
        assert_eq!(
            shorten_typenum("<typenum::never closed>"),
            "<typenum::never closed>"
        );
        assert_eq!(shorten_typenum("plain"), "plain");
    }

    #[test]
    fn lookup_follows_the_old_profiler() {
        let mut symbols = Symbols::new(&[
            symbol(0x100, 0x20, "_ZN4qemu4main17h0000000000000001E"),
            symbol(0x120, 0, "__zero_sized"),
            symbol(0x200, 0x10, "memcpy"),
            symbol(0x200, 0x10, "__aeabi_memcpy"),
            symbol(0x300, 0x40, "_ZN4qemu7profile17h0000000000000002E"),
            symbol(
                0x310,
                0x8,
                "_ZN4qemu7profile28_$u7b$$u7b$closure$u7d$$u7d$17h0000000000000003E",
            ),
        ]);
        let name = |symbols: &mut Symbols, pc| {
            let id = symbols.id(pc);
            symbols.name(id).to_string()
        };
        assert_eq!(name(&mut symbols, 0x100), "qemu::main");
        assert_eq!(name(&mut symbols, 0x11e), "qemu::main");
        // A zero-sized symbol covers two bytes and hides what it sits in.
        assert_eq!(name(&mut symbols, 0x121), "__zero_sized");
        assert_eq!(name(&mut symbols, 0x122), "?122");
        // Same address and size: the greater llvm-nm name wins.
        assert_eq!(name(&mut symbols, 0x204), "memcpy");
        assert_eq!(name(&mut symbols, 0x50), "?50");
        assert_eq!(symbols.id(0x100), symbols.id(0x104));
        assert_eq!(symbols.range_of("qemu::profile"), Some((0x300, 0x340)));
        assert_eq!(symbols.range_of("qemu::prof"), None);
    }
}
