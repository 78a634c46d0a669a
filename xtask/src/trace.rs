//! Attribution of a QEMU `-d in_asm,exec,nochain` trace to functions, the old
//! qemu-profile.py's logic line for line. A translation block's size is read
//! from its `IN:` listing; a block is known by its host address (the `Trace`
//! line's first field), which QEMU logs right after translating it, so a block
//! translated again with other flags (icount splits blocks at I/O) is counted
//! with its own size. The demo ends where `qemu::profile` is first entered;
//! what follows is the profiling replay (game work only).

use std::collections::HashMap;
use std::hash::Hash;

use crate::symbols::Symbols;

/// The compiler's helper routines whose callers are listed.
const HELPERS: [&str; 4] = ["memcpy", "memcmp", "memset", "div"];

/// A counter that remembers first insertion, like Python's `Counter`, so that
/// ties in [`Tally::most_common`] come out in the same order.
pub struct Tally<K> {
    index: HashMap<K, usize>,
    items: Vec<(K, u64)>,
}

impl<K: Hash + Eq + Clone> Tally<K> {
    pub fn new() -> Self {
        Tally {
            index: HashMap::new(),
            items: Vec::new(),
        }
    }

    pub fn add(&mut self, key: K, n: u64) {
        match self.index.get(&key) {
            Some(&i) => self.items[i].1 += n,
            None => {
                self.index.insert(key.clone(), self.items.len());
                self.items.push((key, n));
            }
        }
    }

    pub fn items(&self) -> &[(K, u64)] {
        &self.items
    }

    pub fn total(&self) -> u64 {
        self.items.iter().map(|(_, n)| n).sum()
    }

    /// The `top` largest, ties in insertion order.
    pub fn most_common(&self, top: usize) -> Vec<(K, u64)> {
        let mut sorted = self.items.clone();
        sorted.sort_by_key(|&(_, n)| std::cmp::Reverse(n));
        sorted.truncate(top);
        sorted
    }
}

/// `Trace <n>: 0x<host> [<hex>/<pc>/…`: the host address and the guest pc.
pub fn parse_trace(line: &[u8]) -> Option<(u64, u64)> {
    let rest = line.strip_prefix(b"Trace ")?;
    let rest = skip(rest, |b| b.is_ascii_digit(), 1)?;
    let rest = rest.strip_prefix(b": 0x")?;
    let host_len = run_of(rest, is_lower_hex);
    let host = hex(&rest[..host_len])?;
    let rest = rest[host_len..].strip_prefix(b" [")?;
    let rest = skip(rest, is_lower_hex, 1)?.strip_prefix(b"/")?;
    let pc_len = run_of(rest, is_lower_hex);
    let pc = hex(&rest[..pc_len])?;
    rest[pc_len..].starts_with(b"/").then_some((host, pc))
}

/// The first instruction address of an `IN:` listing line (`0x<8 hex>: …`).
pub fn parse_instruction(line: &[u8]) -> Option<u64> {
    let digits = line.get(2..line.len().min(10))?;
    hex(digits.trim_ascii())
}

fn is_lower_hex(b: u8) -> bool {
    b.is_ascii_digit() || (b'a'..=b'f').contains(&b)
}

fn run_of(bytes: &[u8], class: impl Fn(u8) -> bool) -> usize {
    bytes.iter().take_while(|&&b| class(b)).count()
}

/// `bytes` after at least `min` leading bytes of `class`.
fn skip(bytes: &[u8], class: impl Fn(u8) -> bool, min: usize) -> Option<&[u8]> {
    let n = run_of(bytes, class);
    (n >= min).then(|| &bytes[n..])
}

fn hex(digits: &[u8]) -> Option<u64> {
    u64::from_str_radix(std::str::from_utf8(digits).ok()?, 16).ok()
}

/// A window of the demo counted on its own: from the `from`-th to the `to`-th
/// entry into one of `entries` (1-based, inclusive), up to that function's
/// next entry.
pub struct Window {
    pub entries: Vec<u64>,
    pub from: u64,
    pub to: u64,
    calls: u64,
    /// Instructions from each call in the window to the next, by call.
    per_call: Tally<u64>,
}

impl Window {
    pub fn new(entries: Vec<u64>, from: u64, to: u64) -> Self {
        Window {
            entries,
            from,
            to,
            calls: 0,
            per_call: Tally::new(),
        }
    }
}

/// The running attribution.
pub struct Profile {
    /// Counted as the replay instead of `qemu::profile`, when given.
    window: Option<Window>,
    symbols: Symbols,
    /// `qemu::profile`'s address range (empty when there is none).
    replay: (u64, u64),
    /// Host address → (first pc, instruction count) of a translated block.
    sizes: HashMap<u64, (u64, u64)>,
    /// Host address → the guest address of each instruction of the block.
    listings: HashMap<u64, Vec<u64>>,
    pending: Option<u64>,
    listing: Vec<u64>,
    count: u64,
    /// 0: the demo, 1: the profiling replay.
    phase: usize,
    runs: [Tally<u64>; 2],
    /// (callee, caller) name ids.
    callers: Tally<(usize, usize)>,
    prev: u64,
    helper: HashMap<usize, bool>,
}

impl Profile {
    pub fn new(symbols: Symbols) -> Self {
        let replay = symbols.range_of("qemu::profile").unwrap_or((1, 0));
        Profile {
            window: None,
            symbols,
            replay,
            sizes: HashMap::new(),
            listings: HashMap::new(),
            pending: None,
            listing: Vec::new(),
            count: 0,
            phase: 0,
            runs: [Tally::new(), Tally::new()],
            callers: Tally::new(),
            prev: 0,
            helper: HashMap::new(),
        }
    }

    /// Counts `window` as the second table (`profile`) instead of the replay.
    pub fn with_window(mut self, window: Window) -> Self {
        self.window = Some(window);
        self
    }

    fn is_helper(&mut self, id: usize) -> bool {
        let name = self.symbols.name(id);
        *self
            .helper
            .entry(id)
            .or_insert_with(|| HELPERS.iter().any(|h| name.contains(h)))
    }

    /// One line of the trace.
    pub fn line(&mut self, line: &[u8]) {
        match line.first() {
            Some(b'T') => {
                let Some((host, pc)) = parse_trace(line) else {
                    return;
                };
                if let Some(pending) = self.pending.take() {
                    if pending == pc {
                        self.sizes.insert(host, (pc, self.count));
                        self.listings
                            .insert(host, std::mem::take(&mut self.listing));
                    }
                }
                if let Some(w) = self.window.as_mut() {
                    if w.entries.contains(&pc) {
                        w.calls += 1;
                        self.phase = usize::from(w.from <= w.calls && w.calls <= w.to);
                    }
                } else if self.phase == 0 && self.replay.0 <= pc && pc < self.replay.1 {
                    self.phase = 1;
                }
                self.runs[self.phase].add(host, 1);
                if let Some(w) = self.window.as_mut().filter(|_| self.phase == 1) {
                    let size = self.sizes.get(&host).map_or(0, |&(_, k)| k);
                    w.per_call.add(w.calls, size);
                }
                if self.phase == 0 {
                    let callee = self.symbols.id(pc);
                    if self.is_helper(callee) {
                        let caller = self.symbols.id(self.prev);
                        if caller != callee {
                            self.callers.add((callee, caller), 1);
                        }
                    }
                }
                self.prev = pc;
            }
            Some(b'I') if line.starts_with(b"IN:") => {
                self.pending = None;
                self.count = 0;
                self.listing.clear();
            }
            Some(b'0') if line.starts_with(b"0x") => {
                let Some(address) = parse_instruction(line) else {
                    return;
                };
                if self.pending.is_none() {
                    self.pending = Some(address);
                    self.count = 0;
                    self.listing.clear();
                }
                self.count += 1;
                self.listing.push(address);
            }
            _ => {}
        }
    }

    /// How many times each instruction ran in `phase` (0: the demo or the
    /// benchmark, 1: the profiling replay), by guest address.
    pub fn instruction_counts(&self, phase: usize) -> HashMap<u64, u64> {
        let mut counts = HashMap::new();
        for &(host, n) in self.runs[phase].items() {
            for &pc in self.listings.get(&host).map_or(&[][..], Vec::as_slice) {
                *counts.entry(pc).or_insert(0) += n;
            }
        }
        counts
    }

    /// The tables: instructions by function for the demo and the replay, then
    /// the callers of helper routines during the demo.
    pub fn report(&mut self, top: usize) -> String {
        let mut out = String::new();
        let window = self
            .window
            .as_ref()
            .map(|w| format!("calls {}..={} of the window's function", w.from, w.to));
        let second = window.as_deref().unwrap_or("profile");
        for (phase, name) in ["demo", second].into_iter().enumerate() {
            let mut per = Tally::new();
            let blocks: Vec<(u64, u64)> = self.runs[phase].items().to_vec();
            for (host, n) in blocks {
                let (pc, k) = self.sizes.get(&host).copied().unwrap_or((0, 0));
                per.add(self.symbols.id(pc), n * k);
            }
            let total = per.total();
            out += &format!("== {name}: {total} instructions\n");
            for (id, n) in per.most_common(top) {
                let share = 100.0 * n as f64 / total.max(1) as f64;
                out += &format!("{n:11} {share:5.1}%  {}\n", cut(self.symbols.name(id), 120));
            }
        }
        if let Some(w) = &self.window {
            out += "== the window's costliest calls (call: instructions to the next)\n";
            for (call, n) in w.per_call.most_common(5) {
                out += &format!("{call:11}: {n}\n");
            }
        }
        out += "== helper calls during the demo, by caller\n";
        for ((callee, caller), n) in self.callers.most_common(top) {
            if !self.is_helper(caller) {
                let (callee, caller) = (self.symbols.name(callee), self.symbols.name(caller));
                out += &format!("{n:9}  {} <- {}\n", cut(callee, 40), cut(caller, 90));
            }
        }
        out
    }
}

/// The first `n` characters.
fn cut(text: &str, n: usize) -> &str {
    text.char_indices()
        .nth(n)
        .map_or(text, |(at, _)| &text[..at])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbols::Symbol;

    #[test]
    fn trace_lines() {
        assert_eq!(
            parse_trace(b"Trace 0: 0x7f3a40000100 [00000000/00000400/00000000/ff200000] \n"),
            Some((0x7f3a40000100, 0x400))
        );
        assert_eq!(
            parse_trace(b"Trace 12: 0xabc [0/000000000000040a/0/0]"),
            Some((0xabc, 0x40a))
        );
        assert_eq!(parse_trace(b"Trace x: 0xabc [0/40a/0/0]"), None);
        assert_eq!(parse_trace(b"Trace 0: 0xABC [0/40a/0/0]"), None);
        assert_eq!(parse_trace(b"Trace 0: 0xabc [0/40a]"), None);
        assert_eq!(
            parse_instruction(b"0x0000040a:  b580       push     {r7, lr}\n"),
            Some(0x40a)
        );
        assert_eq!(parse_instruction(b"0x12\n"), Some(0x12));
        assert_eq!(parse_instruction(b"0xzz"), None);
    }

    #[test]
    fn tally_orders_ties_by_first_insertion() {
        let mut tally = Tally::new();
        for (key, n) in [("a", 1), ("b", 3), ("c", 3), ("a", 2), ("d", 0)] {
            tally.add(key, n);
        }
        assert_eq!(tally.most_common(3), [("a", 3), ("b", 3), ("c", 3)]);
        assert_eq!(tally.most_common(5).last(), Some(&("d", 0)));
        assert_eq!(tally.total(), 9);
    }

    fn symbol(address: u64, size: u64, mangled: &str) -> Symbol {
        Symbol {
            address,
            size,
            mangled: mangled.into(),
        }
    }

    /// The second table counts from the 2nd to the 3rd entry into `step`
    /// (`Window`), up to its 4th: the blocks of the 1st and 4th calls are the
    /// demo's.
    #[test]
    fn a_window_counts_the_calls_it_names() {
        let symbols = Symbols::new(&[
            symbol(0x400, 0x10, "_ZN4game4step17h0000000000000001E"),
            symbol(0x500, 0x10, "_ZN4game4draw17h0000000000000002E"),
        ]);
        let entries = symbols.entries_of("step");
        assert_eq!(entries, [0x400]);
        assert!(symbols.entries_of("tep").is_empty());
        let mut profile = Profile::new(symbols).with_window(Window::new(entries, 2, 3));
        let listing = "IN: step
0x00000400:  b580       push     {r7, lr}
0x00000402:  af00       add      r7, sp, #0

Trace 0: 0x10 [00000000/00000400/00000000/ff200000] 
IN: draw
0x00000500:  4770       bx       lr

Trace 0: 0x20 [00000000/00000500/00000000/ff200000] 
";
        let call = "Trace 0: 0x10 [00000000/00000400/00000000/ff200000] \n\
                    Trace 0: 0x20 [00000000/00000500/00000000/ff200000] \n";
        for line in listing
            .split_inclusive('\n')
            .chain(call.split_inclusive('\n').cycle().take(6))
        {
            profile.line(line.trim_start().as_bytes());
        }
        let report = profile.report(5);
        assert!(
            report.starts_with(
                "== demo: 6 instructions\n\
                 \x20         4  66.7%  game::step\n\
                 \x20         2  33.3%  game::draw\n\
                 == calls 2..=3 of the window's function: 6 instructions\n"
            ),
            "{report}"
        );
        assert!(
            report.contains(
                "== the window's costliest calls (call: instructions to the next)\n\
                 \x20         2: 3\n\
                 \x20         3: 3\n"
            ),
            "{report}"
        );
    }

    #[test]
    fn blocks_are_sized_and_attributed() {
        let symbols = Symbols::new(&[
            symbol(0x400, 0x40, "_ZN4qemu4main17h0000000000000001E"),
            symbol(0x500, 0x10, "memcpy"),
            symbol(0x600, 0x20, "_ZN4qemu7profile17h0000000000000002E"),
        ]);
        let trace = "\
----------------
IN: main
0x00000400:  b580       push     {r7, lr}
0x00000402:  af00       add      r7, sp, #0

Trace 0: 0x10 [00000000/00000400/00000000/ff200000] 
----------------
IN: memcpy
0x00000500:  4770       bx       lr

Trace 0: 0x20 [00000000/00000500/00000000/ff200000] 
Trace 0: 0x10 [00000000/00000400/00000000/ff200000] 
Trace 0: 0x20 [00000000/00000500/00000000/ff200000] 
----------------
IN: profile
0x00000600:  b580       push     {r7, lr}
0x00000602:  b580       push     {r7, lr}
0x00000604:  b580       push     {r7, lr}

Trace 0: 0x30 [00000000/00000600/00000000/ff200000] 
Trace 0: 0x10 [00000000/00000400/00000000/ff200000] 
Trace 0: 0x99 [00000000/00000700/00000000/ff200000] 
";
        let mut profile = Profile::new(symbols);
        for line in trace.split_inclusive('\n') {
            profile.line(line.as_bytes());
        }
        assert_eq!(
            profile.report(10),
            "\
== demo: 6 instructions
          4  66.7%  qemu::main
          2  33.3%  memcpy
== profile: 5 instructions
          3  60.0%  qemu::profile
          2  40.0%  qemu::main
          0   0.0%  ?0
== helper calls during the demo, by caller
        2  memcpy <- qemu::main
"
        );
        let counts = profile.instruction_counts(0);
        assert_eq!(counts.get(&0x400), Some(&2));
        assert_eq!(counts.get(&0x402), Some(&2));
        assert_eq!(counts.get(&0x500), Some(&2));
        assert_eq!(counts.get(&0x600), None);
        assert_eq!(profile.instruction_counts(1).get(&0x604), Some(&1));
    }
}
