//! A static bound of the stack a call tree of a Thumb (ARMv6-M) firmware can
//! use, read from the linked ELF: each function's frame from its prologue
//! (`push`, `sub sp, #imm`, `add sp, rN` with a negative literal), its
//! callees from its `bl` instructions, and the deepest path through them.
//!
//! Why static: QEMU's `microbit` TWI is a stub that answers as an MMA8653FC
//! and never fails, so a run measures the stack on that chip's path only;
//! the LSM303AGR's and the FXOS8700CQ's, a failed transfer and the bus clear
//! after it never run there. The call tree of the input task holds every one
//! of them, whichever the board's chip, so its deepest path bounds them all.
//!
//! What it cannot follow it reports: calls through a register (`blx rN`:
//! the executor polling a task, `dyn` methods) end the path there and are
//! counted, recursion is cut (a function already on the path adds nothing),
//! and data inside a function (literal pools, jump tables) that decodes as
//! a frame adjustment only makes the bound larger.

use std::collections::{HashMap, HashSet};

use object::{Object, ObjectSection};

use crate::symbols::{code_symbols, readable};

/// One function's facts.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Function {
    /// Readable name.
    pub name: String,
    /// Bytes its prologue takes off the stack.
    pub frame: u64,
    /// Start addresses of the functions it calls with `bl` (or branches to
    /// outside itself).
    pub calls: Vec<u64>,
    /// Calls through a register.
    pub indirect: u32,
}

/// The functions of a Thumb ELF, by start address.
pub fn functions(elf: &[u8]) -> Result<HashMap<u64, Function>, String> {
    let file = object::File::parse(elf).map_err(|e| e.to_string())?;
    let mut out = HashMap::new();
    let symbols = code_symbols(elf)?;
    for symbol in &symbols {
        if symbol.size < 2 {
            continue;
        }
        let Some(code) = file.sections().find_map(|section| {
            let start = section.address();
            let data = section.data().ok()?;
            let offset = symbol.address.checked_sub(start)?;
            let end = offset.checked_add(symbol.size)?;
            (end <= data.len() as u64).then(|| &data[offset as usize..end as usize])
        }) else {
            continue;
        };
        let mut function = decode(symbol.address, code);
        function.name = readable(&symbol.mangled);
        out.insert(symbol.address, function);
    }
    // Only calls to a function's first instruction are edges.
    let starts: HashSet<u64> = out.keys().copied().collect();
    for function in out.values_mut() {
        function.calls.retain(|target| starts.contains(target));
        function.calls.sort_unstable();
        function.calls.dedup();
    }
    Ok(out)
}

/// The halfwords of `code` (at `address`), little-endian.
fn halfwords(code: &[u8]) -> Vec<u16> {
    code.chunks_exact(2)
        .map(|pair| u16::from_le_bytes([pair[0], pair[1]]))
        .collect()
}

/// Decodes one function's frame and calls (see the module doc).
pub fn decode(address: u64, code: &[u8]) -> Function {
    let words = halfwords(code);
    let end = address + code.len() as u64;
    // Literal words the code loads (`ldr rt, [pc, #imm]`): data, skipped.
    let mut literal = vec![false; words.len()];
    let mut i = 0;
    while i < words.len() {
        let h = words[i];
        if h & 0xF800 == 0x4800 {
            let pc = (address + 2 * i as u64 + 4) & !3;
            let at = pc + 4 * u64::from(h & 0xFF);
            if (address..end.saturating_sub(3)).contains(&at) {
                let index = ((at - address) / 2) as usize;
                literal[index] = true;
                literal[index + 1] = true;
            }
        }
        i += if is_wide(h) { 2 } else { 1 };
    }
    let mut function = Function::default();
    let mut largest_push = 0u64;
    let mut i = 0;
    while i < words.len() {
        let h = words[i];
        if literal[i] {
            i += 1;
            continue;
        }
        let pc = address + 2 * i as u64;
        if is_wide(h) {
            if let Some(&low) = words.get(i + 1) {
                if let Some(target) = bl_target(pc, h, low) {
                    function.calls.push(target);
                }
            }
            i += 2;
            continue;
        }
        if h & 0xFE00 == 0xB400 {
            // push {regs[, lr]}
            let registers = u64::from((h & 0xFF).count_ones()) + u64::from((h >> 8) & 1);
            largest_push = largest_push.max(4 * registers);
        } else if h & 0xFF80 == 0xB080 {
            // sub sp, #imm7 * 4
            function.frame += 4 * u64::from(h & 0x7F);
        } else if h & 0xFF87 == 0x4485 {
            // add sp, rm: a large frame, rm loaded with a negative literal.
            let rm = (h >> 3) & 0xF;
            if let Some(value) = literal_in(&words, address, i, rm) {
                if value < 0 {
                    function.frame += u64::from(value.unsigned_abs());
                }
            }
        } else if h & 0xFF87 == 0x4780 {
            // blx rm
            function.indirect += 1;
        } else if h & 0xF800 == 0xE000 {
            // b: a tail call when it leaves the function.
            let offset = i64::from(((h & 0x7FF) as i16) << 5 >> 4);
            let target = (pc as i64 + 4 + offset) as u64;
            if !(address..end).contains(&target) {
                function.calls.push(target);
            }
        }
        i += 1;
    }
    function.frame += largest_push;
    function
}

/// Whether `h` is the first halfword of a 32-bit instruction.
fn is_wide(h: u16) -> bool {
    matches!(h >> 11, 0b11101..=0b11111)
}

/// The target of a `bl` at `pc` made of `high`, `low`.
fn bl_target(pc: u64, high: u16, low: u16) -> Option<u64> {
    if high & 0xF800 != 0xF000 || low & 0xD000 != 0xD000 {
        return None;
    }
    let s = u32::from((high >> 10) & 1);
    let j1 = u32::from((low >> 13) & 1);
    let j2 = u32::from((low >> 11) & 1);
    let i1 = 1 ^ (j1 ^ s);
    let i2 = 1 ^ (j2 ^ s);
    let imm = (s << 24)
        | (i1 << 23)
        | (i2 << 22)
        | (u32::from(high & 0x3FF) << 12)
        | (u32::from(low & 0x7FF) << 1);
    let offset = ((imm << 7) as i32) >> 7;
    Some((pc as i64 + 4 + i64::from(offset)) as u64)
}

/// The literal the nearest `ldr rm, [pc, #imm]` before halfword `at` loads.
fn literal_in(words: &[u16], address: u64, at: usize, rm: u16) -> Option<i32> {
    (0..at).rev().take(16).find_map(|j| {
        let h = words[j];
        if h & 0xF800 != 0x4800 || (h >> 8) & 7 != rm {
            return None;
        }
        let pc = (address + 2 * j as u64 + 4) & !3;
        let index = ((pc + 4 * u64::from(h & 0xFF) - address) / 2) as usize;
        let low = *words.get(index)?;
        let high = *words.get(index + 1)?;
        Some((u32::from(low) | (u32::from(high) << 16)) as i32)
    })
}

/// The deepest path from `root`: its bytes, the functions on it (root
/// first), and the calls through a register met anywhere below `root`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bound {
    pub bytes: u64,
    pub path: Vec<u64>,
    pub indirect: u32,
}

/// The deepest path from `root` through `functions` (see [`Bound`]).
pub fn deepest(functions: &HashMap<u64, Function>, root: u64) -> Bound {
    let mut memo: HashMap<u64, (u64, Option<u64>)> = HashMap::new();
    let mut on_path = Vec::new();
    depth(functions, root, &mut memo, &mut on_path);
    let mut path = vec![root];
    let mut at = root;
    while let Some(&(_, Some(next))) = memo.get(&at) {
        if path.contains(&next) {
            break;
        }
        path.push(next);
        at = next;
    }
    let indirect = memo
        .keys()
        .filter_map(|address| functions.get(address))
        .map(|function| function.indirect)
        .sum();
    Bound {
        bytes: memo.get(&root).map_or(0, |&(bytes, _)| bytes),
        path,
        indirect,
    }
}

fn depth(
    functions: &HashMap<u64, Function>,
    at: u64,
    memo: &mut HashMap<u64, (u64, Option<u64>)>,
    on_path: &mut Vec<u64>,
) -> u64 {
    if let Some(&(bytes, _)) = memo.get(&at) {
        return bytes;
    }
    let Some(function) = functions.get(&at) else {
        return 0;
    };
    if on_path.contains(&at) {
        return 0;
    }
    on_path.push(at);
    let mut deepest = (0, None);
    for &callee in &function.calls {
        let below = depth(functions, callee, memo, on_path);
        if below > deepest.0 || deepest.1.is_none() {
            deepest = (below, Some(callee));
        }
    }
    on_path.pop();
    let bytes = function.frame + deepest.0;
    memo.insert(at, (bytes, deepest.1));
    bytes
}

/// Every function `root` can reach (itself included).
pub fn reachable(functions: &HashMap<u64, Function>, root: u64) -> HashSet<u64> {
    let mut seen = HashSet::new();
    let mut stack = vec![root];
    while let Some(at) = stack.pop() {
        if !seen.insert(at) {
            continue;
        }
        if let Some(function) = functions.get(&at) {
            stack.extend(function.calls.iter().copied());
        }
    }
    seen
}

/// The deepest stack on the way from `root` down to `target` (both frames
/// counted): `None` if `root` cannot reach it.
pub fn reach(functions: &HashMap<u64, Function>, root: u64, target: u64) -> Option<u64> {
    fn walk(
        functions: &HashMap<u64, Function>,
        at: u64,
        target: u64,
        memo: &mut HashMap<u64, Option<u64>>,
        on_path: &mut Vec<u64>,
    ) -> Option<u64> {
        if let Some(&known) = memo.get(&at) {
            return known;
        }
        let function = functions.get(&at)?;
        if at == target {
            return Some(function.frame);
        }
        if on_path.contains(&at) {
            return None;
        }
        on_path.push(at);
        let below = function
            .calls
            .iter()
            .filter_map(|&callee| walk(functions, callee, target, memo, on_path))
            .max();
        on_path.pop();
        let bytes = below.map(|below| function.frame + below);
        memo.insert(at, bytes);
        bytes
    }
    walk(
        functions,
        root,
        target,
        &mut HashMap::new(),
        &mut Vec::new(),
    )
}

/// Bytes the Cortex-M0 stacks on taking an interrupt (eight registers).
pub const EXCEPTION_FRAME: u64 = 32;

/// The bound of the stack the v1's sensor path can use, every chip's
/// branch, failed transfers and bus clears included (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SensorStack {
    /// `main` down to the executor's call of a task (through a register).
    pub thread_base: u64,
    /// The input task's poll and everything it calls.
    pub input_task: Bound,
    /// The functions on the input task's deepest path, from the task down.
    pub deepest_path: Vec<String>,
    /// Each interrupt handler the firmware has, with the exception frame.
    pub interrupts: Vec<(String, u64)>,
    /// The sensor functions the input task's call tree holds (readable
    /// names), the evidence that the bound is the sensor path's.
    pub covers: Vec<String>,
}

impl SensorStack {
    /// Thread mode plus every interrupt nested on top (as if each could
    /// preempt the others: the bound does not read priorities).
    pub fn total(&self) -> u64 {
        self.thread_base
            + self.input_task.bytes
            + self.interrupts.iter().map(|(_, bytes)| bytes).sum::<u64>()
    }
}

/// [`SensorStack`] of the v1 firmware's ELF: the input task is the
/// executor task (`TaskStorage<F>::poll`) whose call tree holds the sensor
/// wiring (`microbit_v1::sensor`); the interrupt handlers are the vector
/// names (all capitals) that are not the default handler.
pub fn sensor_stack(elf: &[u8]) -> Result<SensorStack, String> {
    let functions = functions(elf)?;
    let main = find_exact(&functions, "main").ok_or("no `main` in the ELF")?;
    let main_tree = reachable(&functions, main);
    let thread_base = main_tree
        .iter()
        .filter(|at| {
            functions
                .get(at)
                .is_some_and(|function| function.indirect > 0)
        })
        .filter_map(|&at| reach(&functions, main, at))
        .max()
        .ok_or("no call through a register below `main` (the executor's poll of a task)")?;
    let is_sensor = |function: &Function| {
        function.name.contains("microbit_v1::sensor") || function.name.contains("microbit_v1::twi")
    };
    let input = functions
        .iter()
        .filter(|(_, function)| function.name.contains("TaskStorage<F>::poll"))
        .filter(|(&at, _)| {
            reachable(&functions, at)
                .iter()
                .any(|callee| functions.get(callee).is_some_and(is_sensor))
        })
        .map(|(&at, _)| deepest(&functions, at))
        .max_by_key(|bound| bound.bytes)
        .ok_or("no executor task whose calls reach `microbit_v1::sensor`")?;
    let default = find_exact(&functions, "DefaultHandler");
    let mut interrupts: Vec<(String, u64)> = functions
        .iter()
        .filter(|(&at, function)| {
            Some(at) != default
                && !function.name.is_empty()
                && function
                    .name
                    .chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        })
        .map(|(&at, function)| {
            (
                function.name.clone(),
                EXCEPTION_FRAME + deepest(&functions, at).bytes,
            )
        })
        .collect();
    interrupts.sort();
    let mut covers: Vec<String> = reachable(&functions, input.path[0])
        .iter()
        .filter_map(|at| functions.get(at))
        .filter(|function| is_sensor(function) || function.name.contains("lsm303"))
        .map(|function| function.name.clone())
        .collect();
    covers.sort();
    let deepest_path = input
        .path
        .iter()
        .filter_map(|at| functions.get(at))
        .map(|function| function.name.clone())
        .collect();
    Ok(SensorStack {
        thread_base,
        input_task: input,
        deepest_path,
        interrupts,
        covers,
    })
}

/// The function named exactly `name`.
fn find_exact(functions: &HashMap<u64, Function>, name: &str) -> Option<u64> {
    functions
        .iter()
        .find(|(_, function)| function.name == name)
        .map(|(&at, _)| at)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(words: &[u16]) -> Vec<u8> {
        words.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// `bl` from `pc` to `target`, as the assembler encodes it.
    fn bl(pc: u64, target: u64) -> [u16; 2] {
        let offset = (target as i64 - (pc as i64 + 4)) as i32 as u32;
        let s = (offset >> 24) & 1;
        let i1 = (offset >> 23) & 1;
        let i2 = (offset >> 22) & 1;
        let j1 = 1 ^ i1 ^ s;
        let j2 = 1 ^ i2 ^ s;
        let high = 0xF000 | (s << 10) | ((offset >> 12) & 0x3FF);
        let low = 0xD000 | (j1 << 13) | (j2 << 11) | ((offset >> 1) & 0x7FF);
        [high as u16, low as u16]
    }

    #[test]
    fn frames_from_push_and_sub_sp() {
        // push {r4, r5, r6, r7, lr}; sub sp, #20; ...; add sp, #20; pop {...}
        let code = bytes(&[0xB5F0, 0xB085, 0x2000, 0xB005, 0xBDF0]);
        let f = decode(0x1000, &code);
        assert_eq!(f.frame, 5 * 4 + 20);
        assert!(f.calls.is_empty());
    }

    #[test]
    fn a_large_frame_from_its_literal() {
        // push {r7, lr}; ldr r0, [pc, #4]; add sp, r0; blx r3; pop; .align; .word -2048
        let code = bytes(&[
            0xB580, 0x4802, 0x4485, 0x4798, 0xBD80, 0x0000, 0xF800, 0xFFFF,
        ]);
        let f = decode(0x2000, &code);
        assert_eq!(f.frame, 8 + 2048);
        assert_eq!(f.indirect, 1);
    }

    #[test]
    fn calls_forward_and_back() {
        for (pc, target) in [(0x1000, 0x1_2346), (0x2_0000, 0x400), (0x800, 0x804)] {
            let [high, low] = bl(pc, target);
            assert_eq!(
                bl_target(pc, high, low),
                Some(target),
                "{pc:#x} -> {target:#x}"
            );
        }
    }

    #[test]
    fn the_deepest_path_adds_the_frames() {
        let mut functions = HashMap::new();
        let mut add = |address: u64, frame: u64, calls: &[u64]| {
            functions.insert(
                address,
                Function {
                    name: format!("f{address:x}"),
                    frame,
                    calls: calls.to_vec(),
                    indirect: 0,
                },
            );
        };
        add(0x100, 16, &[0x200, 0x300]);
        add(0x200, 100, &[0x400]);
        add(0x300, 8, &[0x400, 0x100]); // recursion back to the root: cut
        add(0x400, 40, &[]);
        let bound = deepest(&functions, 0x100);
        assert_eq!(bound.bytes, 16 + 100 + 40);
        assert_eq!(bound.path, vec![0x100, 0x200, 0x400]);
        assert_eq!(reach(&functions, 0x100, 0x400), Some(16 + 100 + 40));
        assert_eq!(reach(&functions, 0x300, 0x200), Some(8 + 16 + 100));
        assert_eq!(reach(&functions, 0x400, 0x100), None);
        assert_eq!(reachable(&functions, 0x200).len(), 2);
    }
    /// A relocatable ARM ELF with `functions` (name, Thumb code) one after
    /// another in `.text`; each `bl` placeholder `(0, index)` in the code is
    /// patched to call function `index`.
    fn elf_of(functions: &[(&str, Vec<u16>)]) -> Vec<u8> {
        use object::write::{Object as Writer, Symbol, SymbolSection};
        use object::{
            Architecture, BinaryFormat, Endianness, SectionKind, SymbolFlags, SymbolKind,
            SymbolScope,
        };
        let mut starts = Vec::new();
        let mut at = 0u64;
        for (_, code) in functions {
            starts.push(at);
            at += 2 * code.len() as u64;
        }
        let mut text = Vec::new();
        for ((_, code), &start) in functions.iter().zip(&starts) {
            let mut words = code.clone();
            let mut i = 0;
            while i < words.len() {
                if words[i] == 0xF000 && words[i + 1] >= 0xD000 {
                    let target = starts[usize::from(words[i + 1] - 0xD000)];
                    let [high, low] = bl(start + 2 * i as u64, target);
                    words[i] = high;
                    words[i + 1] = low;
                    i += 1;
                }
                i += 1;
            }
            text.extend(bytes(&words));
        }
        let mut elf = Writer::new(BinaryFormat::Elf, Architecture::Arm, Endianness::Little);
        let section = elf.add_section(Vec::new(), b".text".to_vec(), SectionKind::Text);
        elf.append_section_data(section, &text, 2);
        for ((name, code), &start) in functions.iter().zip(&starts) {
            elf.add_symbol(Symbol {
                name: name.as_bytes().to_vec(),
                value: start,
                size: 2 * code.len() as u64,
                kind: SymbolKind::Text,
                scope: SymbolScope::Linkage,
                weak: false,
                section: SymbolSection::Section(section),
                flags: SymbolFlags::None,
            });
        }
        elf.write().expect("an ELF in memory")
    }

    #[test]
    fn the_sensor_stack_of_a_small_firmware() {
        const PUSH_R7_LR: u16 = 0xB580;
        const POP_R7_PC: u16 = 0xBD80;
        let elf = elf_of(&[
            // 0: main -> 1
            ("main", vec![PUSH_R7_LR, 0xF000, 0xD001, POP_R7_PC]),
            // 1: the executor: a task through a register
            ("executor::run", vec![0xB510, 0x4798, 0xBD10]),
            // 2: the input task -> 3
            (
                "embassy_executor::raw::TaskStorage<F>::poll",
                vec![0xB5F0, 0xB082, 0xF000, 0xD003, 0xB002, 0xBDF0],
            ),
            // 3: the sensor's bus wait
            (
                "microbit_v1::sensor::Twi::wait",
                vec![PUSH_R7_LR, 0xB084, 0xB004, POP_R7_PC],
            ),
            // 4: another task, deeper, without the sensor
            (
                "embassy_executor::raw::TaskStorage<F>::poll",
                vec![PUSH_R7_LR, 0xB0FF, 0xB07F, POP_R7_PC],
            ),
            ("TIMER0", vec![PUSH_R7_LR, POP_R7_PC]),
            ("DefaultHandler", vec![0xE7FE]),
        ]);
        let stack = sensor_stack(&elf).expect("a bound");
        assert_eq!(stack.thread_base, 8 + 8);
        assert_eq!(stack.input_task.bytes, 20 + 8 + 8 + 16);
        assert_eq!(stack.interrupts, vec![("TIMER0".to_string(), 32 + 8)]);
        assert_eq!(stack.total(), 16 + 52 + 40);
        assert_eq!(
            stack.covers,
            vec!["microbit_v1::sensor::Twi::wait".to_string()]
        );
        assert_eq!(stack.deepest_path.len(), 2);
        // Without the sensor's functions there is no input task to bound.
        let elf = elf_of(&[
            ("main", vec![PUSH_R7_LR, 0xF000, 0xD001, POP_R7_PC]),
            ("executor::run", vec![0xB510, 0x4798, 0xBD10]),
            (
                "embassy_executor::raw::TaskStorage<F>::poll",
                vec![PUSH_R7_LR, POP_R7_PC],
            ),
        ]);
        assert!(sensor_stack(&elf)
            .unwrap_err()
            .contains("microbit_v1::sensor"));
    }
}
