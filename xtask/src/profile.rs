//! `cargo xtask qemu-profile [TOP] [--v1 [--scenes] | --bench SCENE]`: where the QEMU
//! firmware's instructions go, by function (the mps2-an386 board's, or with
//! `--v1` the micro:bit v1's in QEMU microbit, with `--scenes` its `--demo
//! --profile` run and so the stress scenes too, or with `--bench` the study's
//! Cortex-M4F benchmark running one scene with the firmware's backend and
//! event stepping: where `cargo accuracy`'s M4 instructions per step go; any
//! board of [`crate::boards`] with a QEMU machine can be profiled, its
//! headless command line being the runner's). Runs the headless demo with QEMU's translation-block trace on
//! (`-d in_asm,exec,nochain`: every executed block is logged, chaining off so
//! none is skipped) and attributes every executed instruction to the function
//! holding it (see trace.rs). A second pair of tables follows the DWARF
//! inline records (the `addr2line` crate): each instruction is counted for
//! the function of ours it was written in, however deeply the optimiser
//! inlined it (a task's `poll` holds most of the firmware), and for an area
//! of the firmware (display, physics, autopilot, …). The trace is large (about 2 GB for the whole
//! demo, in PROFILE_DIR, default `<target>/qemu-profile`; deleted afterwards
//! unless KEEP_TRACE=1), so it is streamed, never loaded whole.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::Stdio;

use crate::boards::{Board, Firmware};
use crate::error::{say, Failure, Outcome};
use crate::process;
use crate::runner::{self, Load};
use crate::setup;
use crate::symbols::{self, Symbols};
use crate::trace::{Profile, Tally, Window};
use crate::workspace;

/// The study's scenes, in `study::SceneId` order (the benchmark's
/// `--scenes` mask bits).
pub const SCENES: [&str; 4] = ["incline", "bounce", "maze", "corner"];

/// What to profile.
#[derive(Clone, Copy, Debug)]
pub enum Subject {
    /// A board's headless demo in its QEMU machine.
    Demo(&'static Board),
    /// A board's `--demo --profile` run, built with its profile feature (the
    /// micro:bit v1's: the levels, then the difficulty-9 mazes and the
    /// stress scenes).
    Scenes(&'static Board),
    /// A board's benchmark, one scene (index in [`SCENES`]), backend i8f24,
    /// event stepping (the study's scene mask; QEMU mps2-an386's is the M4's).
    Bench(&'static Board, usize),
}

impl Subject {
    /// The board it runs on and the firmware.
    fn firmware(self) -> Result<(&'static Board, &'static Firmware), Failure> {
        match self {
            Subject::Demo(board) | Subject::Scenes(board) => Ok((board, &board.game)),
            Subject::Bench(board, _) => match &board.bench {
                Some(bench) => Ok((board, bench)),
                None => Err(Failure::new(format!("the {} has no benchmark", board.name))),
            },
        }
    }
}

/// Runs, attributes, prints the tables on stdout. With `window`
/// (`FUNCTION:FROM-TO`), the second table and the by-source tables count only
/// the calls FROM to TO (1-based) of FUNCTION and what runs until its next call:
/// `step_events:1933-2230` is grand-tour's frames in the v1 demo (the frames of
/// the levels before it summed, as `check-microbit-v1` lists them).
pub fn run(top: usize, subject: Subject, window: Option<&str>) -> Outcome {
    let (board, firmware) = subject.firmware()?;
    let machine = board.machine()?;
    let qemu = setup::qemu()?;
    let elf = match subject {
        Subject::Scenes(_) => firmware.build_profiled()?,
        _ => firmware.build()?,
    };
    let dir = workspace::env_path("PROFILE_DIR", workspace::target_dir()?.join("qemu-profile"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    let trace = dir.join("trace.log");
    let defmt = File::create(dir.join("defmt.bin"))
        .map_err(|e| Failure::new(format!("cannot write in {}: {e}", dir.display())))?;

    let demo = match subject {
        Subject::Bench(_, scene) => vec![
            "--backends=1".to_string(),
            "--rates=1".to_string(),
            format!("--scenes={}", 1u32 << scene),
            "--variants=0".to_string(),
        ],
        Subject::Scenes(_) => vec!["--demo".to_string(), "--profile".to_string()],
        Subject::Demo(_) => vec!["--demo".to_string()],
    };
    let mut cmd = runner::headless_command(machine, &qemu, &Load::Elf(&elf), &demo);
    cmd.args(["-d", "in_asm,exec,nochain", "-D"])
        .arg(&trace)
        .stdin(Stdio::null())
        .stdout(defmt);
    say!(
        "tracing the {} in QEMU (up to 2 GB in {})…",
        match subject {
            Subject::Bench(_, scene) => format!("benchmark's {} scene", SCENES[scene]),
            _ => "headless demo".to_string(),
        },
        trace.display()
    );
    let status = process::status(&mut cmd)?;
    if !status.success() {
        return Err(Failure::new(format!(
            "QEMU exited with status {} (`{}`)",
            process::code(status),
            process::shown(&cmd)
        )));
    }

    let data = std::fs::read(&elf)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", elf.display())))?;
    let symbols = symbols::code_symbols(&data)
        .map_err(|e| Failure::new(format!("cannot read the symbols of {}: {e}", elf.display())))?;
    let symbols = Symbols::new(&symbols);
    let window = match window {
        Some(text) => Some(parse_window(text, &symbols)?),
        None => None,
    };
    let counted = usize::from(window.is_some());
    let mut profile = Profile::new(symbols);
    if let Some(window) = window {
        profile = profile.with_window(window);
    }
    say!("attributing the trace to functions…");
    let file = File::open(&trace)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", trace.display())))?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let mut line = Vec::with_capacity(256);
    loop {
        line.clear();
        match reader.read_until(b'\n', &mut line) {
            Ok(0) => break,
            Ok(_) => profile.line(&line),
            Err(e) => return Err(Failure::new(format!("reading {}: {e}", trace.display()))),
        }
    }
    print!("{}", profile.report(top));
    print!(
        "{}",
        by_source(&elf, &profile.instruction_counts(counted), top)?
    );
    if std::env::var("KEEP_TRACE").as_deref() != Ok("1") {
        let _ = std::fs::remove_file(&trace);
    }
    Ok(0)
}

/// `FUNCTION:FROM-TO` as a [`Window`] on the entries of every function named
/// `…::FUNCTION`.
fn parse_window(text: &str, symbols: &Symbols) -> Result<Window, Failure> {
    let bad = || {
        Failure::new(format!(
            "--window {text}: expected FUNCTION:FROM-TO (say step_events:1933-2230), FROM ≥ 1, TO ≥ FROM"
        ))
    };
    let (function, range) = text.rsplit_once(':').ok_or_else(bad)?;
    let (from, to) = range.split_once('-').ok_or_else(bad)?;
    let (from, to): (u64, u64) = (
        from.trim().parse().map_err(|_| bad())?,
        to.trim().parse().map_err(|_| bad())?,
    );
    if from == 0 || to < from {
        return Err(bad());
    }
    let entries = symbols.entries_of(function);
    if entries.is_empty() {
        return Err(Failure::new(format!(
            "--window {text}: no function named …::{function} in the firmware"
        )));
    }
    Ok(Window::new(entries, from, to))
}

/// The areas of the firmware, by what the name of the function an instruction
/// was written in contains (first match wins).
const AREAS: [(&str, &[&str]); 13] = [
    (
        "measurement (CPU meter, stack paint)",
        &["cpu_meter", "::stack::"],
    ),
    // What stands in for hardware QEMU lacks (runs in the firmware, but on a
    // board the chip or the LEDs themselves do it).
    (
        "QEMU hardware models (virtual accelerometer and I2C, LED on-time)",
        &["virtual_", "OnTimeIntegrator"],
    ),
    ("display (frame loads, scanning)", &["matrix::", "Matrix"]),
    ("render", &["render::"]),
    ("autopilot", &["autopilot"]),
    ("physics", &["physics::"]),
    ("records", &["records"]),
    ("sound", &["sound"]),
    (
        "input and sensor",
        &["input::", "sensor", "lsm303", "i2c", "I2c"],
    ),
    ("game (rules, session, player)", &["game::"]),
    (
        "executor and time",
        &[
            "embassy",
            "clock",
            "executor",
            "SysTick",
            "critical_section",
            "cortex_m",
        ],
    ),
    (
        "compiler helpers (memcpy, division)",
        &["compiler_builtins", "aeabi", "mem"],
    ),
    ("app glue (tasks, board)", &["app::", "qemu", "microbit"]),
];

/// The area of a function (its readable name), or "other".
pub fn area(function: &str) -> &'static str {
    AREAS
        .iter()
        .find(|(_, keys)| keys.iter().any(|key| function.contains(key)))
        .map_or("other", |(name, _)| name)
}

/// Whether a function belongs to the Rust standard library (or is a method of
/// a primitive type) or to a fixed-point or container crate: such code is
/// counted for the function of ours that called it.
pub fn is_library(function: &str) -> bool {
    let name = function.trim_start_matches(['<', '&', '(', '*']);
    let name = name.strip_prefix("mut ").unwrap_or(name);
    let name = name.strip_prefix("const ").unwrap_or(name);
    let first = name.split([':', '>', ' ', '<']).next().unwrap_or("");
    // A blanket impl over a type parameter (`<&mut I as Iterator>::next`).
    let generic = first.len() == 1 && first.starts_with(|c: char| c.is_ascii_uppercase());
    name.starts_with('[')
        || generic
        || [
            "core",
            "alloc",
            "std",
            "u8",
            "u16",
            "u32",
            "u64",
            "u128",
            "usize",
            "i8",
            "i16",
            "i32",
            "i64",
            "i128",
            "isize",
            "bool",
            "char",
            "f32",
            "f64",
            "str",
            "fixed",
            "typenum",
            "az",
            "heapless",
            "micromath",
        ]
        .contains(&first)
}

/// The instructions of `counts` by the function of ours each was written in
/// (the innermost inline frame that is not the standard library's; the
/// outermost when all are) and by area.
fn by_source(elf: &Path, counts: &HashMap<u64, u64>, top: usize) -> Result<String, Failure> {
    let loader = addr2line::Loader::new(elf).map_err(|e| {
        Failure::new(format!(
            "cannot read the debug info of {}: {e}",
            elf.display()
        ))
    })?;
    let mut functions = Tally::new();
    let mut areas = Tally::new();
    let mut pcs: Vec<(u64, u64)> = counts.iter().map(|(&pc, &n)| (pc, n)).collect();
    pcs.sort_unstable();
    for (pc, n) in pcs {
        let mut names = Vec::new();
        if let Ok(mut frames) = loader.find_frames(pc) {
            while let Ok(Some(frame)) = frames.next() {
                if let Some(name) = frame.function.as_ref().and_then(|f| f.demangle().ok()) {
                    names.push(name.into_owned());
                }
            }
        }
        let name = names
            .iter()
            .find(|name| !is_library(name))
            .or(names.last())
            .cloned()
            .or_else(|| loader.find_symbol(pc).map(symbols::readable))
            .unwrap_or_else(|| format!("?{pc:#x}"));
        areas.add(area(&name), n);
        functions.add(name, n);
    }
    let total = functions.total().max(1);
    let share = |n: u64| 100.0 * n as f64 / total as f64;
    let mut out =
        format!("== by area (inlined code counted where it was written): {total} instructions\n");
    for (name, n) in areas.most_common(AREAS.len() + 1) {
        out += &format!("{n:11} {:5.1}%  {name}\n", share(n));
    }
    out += "== by source function (inlined code counted where it was written)\n";
    for (name, n) in functions.most_common(top) {
        let name: String = name.chars().take(120).collect();
        out += &format!("{n:11} {:5.1}%  {name}\n", share(n));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_frames_are_skipped() {
        for name in [
            "core::option::Option<&T>::copied",
            "<usize as core::slice::index::SliceIndex<[T]>>::get_mut",
            "<u32>::saturating_add",
            "<core::ops::range::Range<T> as core::iter::range::RangeIteratorImpl>::spec_next",
            "<[T]>::iter",
            "<fixed::FixedI32<typenum::uint::UInt<typenum::uint::UTerm>> as core::ops::Mul>::mul",
            "<&mut I as core::iter::traits::iterator::Iterator>::next",
        ] {
            assert!(is_library(name), "{name}");
        }
        for name in [
            "marble_rolling::matrix::OnTimeIntegrator<_,_>::feed",
            "<marble_rolling::board::qemu::virtual_matrix::VirtualMatrix<C> as marble_rolling::app::MatrixOutput<_,_>>::show_refresh",
            "embassy_executor::raw::TaskStorage<F>::poll",
            "qemu::profile",
            "__aeabi_memcpy4",
        ] {
            assert!(!is_library(name), "{name}");
        }
    }

    #[test]
    fn windows_name_a_function_and_a_range_of_its_calls() {
        let symbols = Symbols::new(&[symbols::Symbol {
            address: 0x401,
            size: 0x10,
            mangled: "_ZN4game11step_events17h0000000000000001E".into(),
        }]);
        let w = parse_window("step_events:3-7", &symbols).expect("a window");
        assert_eq!((w.entries.as_slice(), w.from, w.to), (&[0x400][..], 3, 7));
        for bad in [
            "step_events",
            "step_events:0-3",
            "step_events:5-4",
            "step_events:a-4",
        ] {
            let e = parse_window(bad, &symbols).err().expect(bad).message;
            assert!(e.contains("FUNCTION:FROM-TO"), "{bad}: {e}");
        }
        let e = parse_window("step:1-2", &symbols)
            .err()
            .expect("no such function")
            .message;
        assert!(e.contains("no function named …::step"), "{e}");
    }

    #[test]
    fn areas() {
        assert_eq!(
            area("<marble_rolling::board::qemu::virtual_matrix::VirtualMatrix<C> as marble_rolling::app::MatrixOutput<_,_>>::show_refresh"),
            "QEMU hardware models (virtual accelerometer and I2C, LED on-time)"
        );
        assert_eq!(area("marble_rolling::physics::world::events::<impl marble_rolling::physics::world::World<S,_>>::search"), "physics");
        assert_eq!(area("marble_rolling::game::autopilot::solid"), "autopilot");
        assert_eq!(
            area("marble_rolling::game::session::Session<S>::frame_in"),
            "game (rules, session, player)"
        );
        assert_eq!(
            area("marble_qemu::clock::embassy_ticks"),
            "executor and time"
        );
        assert_eq!(
            area("__aeabi_memcpy4"),
            "compiler helpers (memcpy, division)"
        );
        assert_eq!(
            area("marble_qemu::cpu_meter::count_instructions"),
            "measurement (CPU meter, stack paint)"
        );
        assert_eq!(
            area("lsm303agr::device_impl::acceleration"),
            "input and sensor"
        );
        assert_eq!(
            area("marble_rolling::matrix::OnTimeIntegrator<_,_>::feed"),
            "QEMU hardware models (virtual accelerometer and I2C, LED on-time)"
        );
        assert_eq!(
            area("marble_rolling::board::virtual_lsm303agr::VirtualLsm303agr::read_accel"),
            "QEMU hardware models (virtual accelerometer and I2C, LED on-time)"
        );
        assert_eq!(
            area("marble_rolling::matrix::Scanner<_,_>::next_step"),
            "display (frame loads, scanning)"
        );
        assert_eq!(area("zzz"), "other");
    }
}
