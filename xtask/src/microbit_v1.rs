//! The micro:bit v1 tasks (`boards/microbit-v1`, nRF51822, thumbv6m-none-eabi):
//!
//! * [`run`] — `cargo microbit-v1`: build, then `probe-rs run --chip
//!   nRF51822_xxAA` on a board (probe-rs is never installed for you:
//!   `cargo install probe-rs-tools --locked`); with `--demo` (or `--qemu`)
//!   the same ELF runs headless in `qemu-system-arm -M microbit` instead,
//!   its defmt log (semihosting) decoded by defmt-print.
//! * [`check`] — `cargo xtask check-microbit-v1`: the QEMU demo against the
//!   host simulator (outcome, steps and `state_hash` per level), the LEDs
//!   rebuilt from QEMU's GPIO trace against the frames the firmware says it
//!   showed, the sensor path in the demo (`accel=mma8653fc` through QEMU's
//!   TWI stub, its re-init and fault counts), a `--demo --profile` run's
//!   per-level frame costs (printed; the 60 000-instruction worst frame is
//!   the physics' goal), a two-second play without the demo (the stub found
//!   as the MMA8653FC, polled without a panic, the LEDs showing what the
//!   supervision decided), and the budgets (RAM: statics + stack
//!   high-water ≤ V1_RAM_BUDGET, 12 KiB; flash ≤ V1_FLASH_BUDGET, 128 KiB,
//!   with the code bytes per module when over; CPU ≤
//!   V1_CPU_BUDGET_CENTIPERCENT, 20 % of 16 MHz).
//!
//! # The display, rebuilt from the GPIO trace
//!
//! QEMU runs with `-trace nrf51_gpio_update_output_irq -trace
//! nrf51_timer_set_count -D FILE`: one line per pin change (the firmware
//! writes the 12 matrix pins with one `OUT` write per BCM slice) and one
//! per TIMER capture. The firmware's display interrupt captures TIMER0 (its
//! 1 MHz clock) right before each `OUT` write, so the latest capture before
//! a pin change is that change's time in µs ([`Timeline`]; the 32-bit
//! counter is extended across wraps). The firmware logs each frame that
//! stayed on the LEDs for 80 ms or more as `display frame level=L t0=T0
//! t1=T1 rows=R0 R1 R2 R3 R4` (five hex digits per row, brightness 0..=15),
//! [`Timeline::perceived`] integrates the pin levels over `[T0, T1)`: each
//! LED's lit time (its row pin high and its column pin low, through the
//! DAL's table in `src/board/microbit_v1/leds.rs`, included here) over the
//! time its row was driven, × 15, rounded — what a viewer sees, as the
//! mps2 board's virtual matrix computes it. The check wants every logged
//! frame matched within one level per pixel (interrupt latency moves slice
//! edges by a microsecond or two), and per level at least one frame that
//! shows the maze and the marble (not blank, not the all-on win flash).

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::demo::{self, Level};
use crate::error::{say, Failure, Outcome};
use crate::firmware::{self, Artifact};
use crate::process;
use crate::runner;
use crate::setup::{self, M0};
use crate::workspace;

/// The firmware's own LED table (`leds::LED_MAP`, `decode_levels`), the very
/// file the firmware compiles: the check and the firmware cannot disagree
/// on the wiring (the table itself is tested against the DAL's in the core's
/// tests).
#[allow(dead_code)]
#[path = "../../src/board/microbit_v1/leds.rs"]
mod leds;
mod gpio_trace;

pub use gpio_trace::{hex_rows, max_difference, parse_frame, LoggedFrame, Timeline};

/// The firmware crate and binary.
pub const PACKAGE: &str = "marble-microbit-v1";
/// The firmware binary.
pub const BIN: &str = "microbit-v1";
/// probe-rs's name for the micro:bit v1's chip.
pub const CHIP: &str = "nRF51822_xxAA";

/// Budgets (bytes, hundredths of a percent), overridable from the environment.
const RAM_BUDGET: u64 = 12 * 1024;
const FLASH_BUDGET: u64 = 128 * 1024;
const CPU_BUDGET_CENTIPERCENT: u64 = 2000;

/// Tolerance of the rebuilt frames, brightness levels per pixel.
const FRAME_TOLERANCE: u8 = 1;

/// `cargo microbit-v1 [ARGS]`: on a board with probe-rs, or in QEMU with
/// `--demo` / `--qemu` (the rest of ARGS go to the firmware's semihosting
/// command line there, to probe-rs after the ELF otherwise).
pub fn run(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let (image, args) = take_image(args)?;
    let qemu = args.iter().any(|arg| arg == "--demo" || arg == "--qemu");
    setup::target(M0)?;
    if qemu {
        let limit = runner::timeout(600)?;
        let tools = setup::m4_qemu()?;
        let elf = build()?;
        let firmware_args: Vec<String> = args.into_iter().filter(|arg| arg != "--qemu").collect();
        say!("running it headless in QEMU microbit (defmt log below)");
        let (status, _) = match &image {
            Some(image) => {
                say!(
                    "flash loaded from {} (the ELF only decodes the log)",
                    image.display()
                );
                let cmd = qemu_image_command(&tools.qemu, image, &firmware_args);
                qemu_run_with(cmd, &tools, &elf, None, Sink::Terminal, limit)?
            }
            None => qemu_run(&tools, &elf, &firmware_args, None, Sink::Terminal, limit)?,
        };
        return Ok(status);
    }
    if image.is_some() {
        return Err(Failure::new(
            "--image runs a flash image in QEMU: give --demo or --qemu with it (on a board, \
             drag the .hex onto MICROBIT instead)",
        )
        .status(2));
    }
    let elf = build()?;
    let probe = setup::probe_rs()?;
    say!("running it on the micro:bit v1 with probe-rs");
    let mut cmd = Command::new(probe);
    cmd.args(["run", "--chip", CHIP]).arg(&elf).args(&args);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        let error = cmd.exec();
        Err(Failure::new(format!("cannot run `{}`: {error}", process::shown(&cmd))).status(127))
    }
    #[cfg(not(unix))]
    Ok(process::code(process::status(&mut cmd)?))
}

/// Builds the firmware (`-p marble-microbit-v1 --target thumbv6m-none-eabi
/// --release`).
fn build() -> Result<PathBuf, Failure> {
    firmware::build(&Artifact::firmware(PACKAGE, BIN, M0))
}

/// Where a QEMU run's decoded log goes.
enum Sink<'a> {
    Terminal,
    File(&'a File),
}

impl Sink<'_> {
    fn stdio(&self) -> Result<Stdio, Failure> {
        match self {
            Sink::Terminal => Ok(Stdio::inherit()),
            Sink::File(file) => Ok(file
                .try_clone()
                .map_err(|e| Failure::new(format!("cannot share the log file: {e}")))?
                .into()),
        }
    }
}

/// The QEMU command line (without the trace options).
pub fn qemu_command(qemu: &Path, elf: &Path, args: &[String]) -> Command {
    let program = elf
        .file_name()
        .map(|name| name.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut cmd = qemu_machine(qemu, &program, args);
    cmd.arg("-kernel").arg(elf);
    cmd
}

/// The QEMU command line for a flash image (`.hex`, as a person drags onto
/// the board, or ELF) put in place by QEMU's generic loader instead of
/// `-kernel`: the Cortex-M0 then boots from the vector table it wrote, as
/// the nRF51 does from flash. The firmware sees BIN as its program name.
pub fn qemu_image_command(qemu: &Path, image: &Path, args: &[String]) -> Command {
    let mut cmd = qemu_machine(qemu, BIN, args);
    let mut loader = std::ffi::OsString::from("loader,file=");
    // QEMU's option syntax: a comma inside a value is doubled.
    loader.push(image.to_string_lossy().replace(',', ",,"));
    cmd.arg("-device").arg(loader);
    cmd
}

/// `--image PATH` (or `--image=PATH`) taken out of the arguments.
pub fn take_image(args: Vec<String>) -> Result<(Option<PathBuf>, Vec<String>), Failure> {
    let mut image = None;
    let mut rest = Vec::with_capacity(args.len());
    let mut args = args.into_iter();
    while let Some(arg) = args.next() {
        let path = match arg.strip_prefix("--image") {
            Some("") => args
                .next()
                .ok_or_else(|| Failure::new("--image needs a file (a .hex or an ELF)").status(2))?,
            Some(value) if value.starts_with('=') => value[1..].to_string(),
            _ => {
                rest.push(arg);
                continue;
            }
        };
        if image.replace(PathBuf::from(path)).is_some() {
            return Err(Failure::new("--image given twice").status(2));
        }
    }
    Ok((image, rest))
}

/// QEMU's microbit machine, headless, its semihosting command line `program`
/// + `args`; no firmware yet.
fn qemu_machine(qemu: &Path, program: &str, args: &[String]) -> Command {
    let mut cmd = Command::new(qemu);
    cmd.args([
        "-M",
        "microbit",
        "-display",
        "none",
        "-monitor",
        "none",
        "-nodefaults",
    ])
    .args(runner::ICOUNT)
    .arg("-semihosting-config")
    .arg(runner::semihosting_config(program, args));
    cmd
}

/// Runs the ELF in QEMU microbit, headless, `trace` (if any) receiving the
/// GPIO and TIMER-capture trace; the defmt log (QEMU's stdout) through
/// defmt-print to `sink`. QEMU's status (the firmware's), else defmt-print's.
fn qemu_run(
    tools: &setup::Qemu,
    elf: &Path,
    args: &[String],
    trace: Option<&Path>,
    sink: Sink,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    let qemu = qemu_command(&tools.qemu, elf, args);
    qemu_run_with(qemu, tools, elf, trace, sink, limit)
}

/// Runs the flash image `image` (see [`qemu_image_command`]) headless with
/// `args`, its defmt log decoded with `elf` (which must be the image's ELF)
/// into `log`: QEMU's status (the firmware's), else defmt-print's.
pub fn run_image(
    tools: &setup::Qemu,
    elf: &Path,
    image: &Path,
    args: &[String],
    log: &File,
    limit: Duration,
) -> Result<u8, Failure> {
    let qemu = qemu_image_command(&tools.qemu, image, args);
    let (status, _) = qemu_run_with(qemu, tools, elf, None, Sink::File(log), limit)?;
    Ok(status)
}

/// [`qemu_run`] for a QEMU command line already made.
fn qemu_run_with(
    mut qemu: Command,
    tools: &setup::Qemu,
    elf: &Path,
    trace: Option<&Path>,
    sink: Sink,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    if let Some(trace) = trace {
        qemu.args(["-trace", "nrf51_gpio_update_output_irq"])
            .args(["-trace", "nrf51_timer_set_count"])
            .arg("-D")
            .arg(trace);
    }
    qemu.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(sink.stdio()?);
    let started = Instant::now();
    let mut child = process::spawn(&mut qemu)?;
    let Some(pipe) = child.stdout.take() else {
        return Err(Failure::new("QEMU's stdout was not piped"));
    };
    let mut decode = Command::new(&tools.defmt_print);
    decode
        .arg("-e")
        .arg(elf)
        .stdin(pipe)
        .stdout(sink.stdio()?)
        .stderr(sink.stdio()?);
    let mut decoder = process::spawn(&mut decode).inspect_err(|_| {
        let _ = child.kill();
    })?;
    let qemu_status = runner::wait_at_most(&mut child, limit);
    let decoder_status = decoder
        .wait()
        .map_err(|e| Failure::new(format!("waiting for defmt-print: {e}")))?;
    let qemu_status = qemu_status?;
    let status = match process::code(qemu_status) {
        0 => process::code(decoder_status),
        code => code,
    };
    Ok((status, started.elapsed()))
}

// ---------------------------------------------------------------------------
// Budgets in the log
// ---------------------------------------------------------------------------

/// `ram: statics S B + stack high-water H B = T B …` → (statics, stack).
pub fn parse_ram(log: &str) -> Option<(u64, u64)> {
    log.lines().find_map(|line| {
        let rest = &line[line.find("ram: statics ")? + "ram: statics ".len()..];
        let (statics, rest) = rest.split_once(" B + stack high-water ")?;
        let (stack, _) = rest.split_once(" B")?;
        Some((statics.parse().ok()?, stack.parse().ok()?))
    })
}

/// `cpu load: … = X.YY % of a 16 MHz …` → hundredths of a percent.
pub fn parse_cpu(log: &str) -> Option<u64> {
    log.lines().find_map(|line| {
        let rest = &line[line.find("cpu load: ")?..];
        let end = rest.find(" % of a 16 MHz")?;
        let number = rest[..end].rsplit(' ').next()?;
        let (whole, cents) = number.split_once('.')?;
        if cents.len() != 2 {
            return None;
        }
        Some(whole.parse::<u64>().ok()? * 100 + cents.parse::<u64>().ok()?)
    })
}

/// Code bytes per crate and top module (`marble_rolling::physics`,
/// `core::fmt`, …), largest first: where the flash goes.
pub fn bloat(elf: &[u8]) -> Result<Vec<(String, u64)>, String> {
    let mut totals: std::collections::BTreeMap<String, u64> = std::collections::BTreeMap::new();
    for symbol in crate::symbols::code_symbols(elf)? {
        let name = crate::symbols::readable(&symbol.mangled);
        *totals.entry(module_of(&name)).or_default() += symbol.size;
    }
    let mut list: Vec<(String, u64)> = totals.into_iter().collect();
    list.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    Ok(list)
}

/// The first two path segments of a demangled name (the type's, for an
/// `<impl …>` or `<T as Trait>` name).
pub fn module_of(name: &str) -> String {
    let name = name.trim_start_matches('<').trim_start_matches("impl ");
    let path: String = name
        .chars()
        .take_while(|&c| c.is_alphanumeric() || c == '_' || c == ':')
        .collect();
    let mut segments = path.split("::").filter(|s| !s.is_empty());
    match (segments.next(), segments.next()) {
        (Some(first), Some(second)) => format!("{first}::{second}"),
        (Some(first), None) if path.contains("::") => first.to_string(),
        _ => "(symbols without a path: vectors, handlers, builtins)".to_string(),
    }
}

// ---------------------------------------------------------------------------
// The check
// ---------------------------------------------------------------------------

/// Collects the problems; each is reported when found.
#[derive(Default)]
struct Problems(Vec<String>);

impl Problems {
    fn report(&mut self, message: String) {
        say!("{message}");
        self.0.push(message);
    }
}

/// `cargo xtask check-microbit-v1`: see the module doc.
pub fn check() -> Outcome {
    let target = workspace::target_dir()?;
    let log_path = workspace::env_path("CHECK_V1_LOG", target.join("check-microbit-v1.log"));
    let trace_path = workspace::env_path("CHECK_V1_TRACE", target.join("check-microbit-v1.trace"));
    let ram_budget = workspace::env_number("V1_RAM_BUDGET", RAM_BUDGET)?;
    let flash_budget = workspace::env_number("V1_FLASH_BUDGET", FLASH_BUDGET)?;
    let cpu_budget = workspace::env_number("V1_CPU_BUDGET_CENTIPERCENT", CPU_BUDGET_CENTIPERCENT)?;
    let limit = runner::timeout(600)?;
    let mut problems = Problems::default();

    setup::target(M0)?;
    let tools = setup::m4_qemu()?;
    let elf = build()?;
    if let Some(dir) = log_path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    }
    let file = File::create(&log_path)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", log_path.display())))?;
    say!("running the demo in QEMU microbit with the GPIO trace…");
    let demo_args = ["--demo".to_string()];
    let (status, took) = match qemu_run(
        &tools,
        &elf,
        &demo_args,
        Some(&trace_path),
        Sink::File(&file),
        limit,
    ) {
        Ok(done) => done,
        Err(failure) if failure.status == 124 => (124, limit),
        Err(failure) => return Err(failure),
    };
    let text = std::fs::read(&log_path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", log_path.display())))?;
    let text = demo::strip_colours(&String::from_utf8_lossy(&text));
    let _ = std::fs::write(&log_path, &text);
    say!("QEMU ran for {:.1} s of host time", took.as_secs_f64());
    if status != 0 {
        problems.report(format!(
            "the demo exited with status {status} (log: {})",
            log_path.display()
        ));
    }

    // 1. Every level as the simulator plays it.
    let (levels, total) = demo::parse_levels(&text);
    if levels.is_empty() {
        return Err(Failure::new(format!(
            "no per-level lines in the log ({})",
            log_path.display()
        )));
    }
    if let Some(total) = total.filter(|&total| total != levels.len()) {
        problems.report(format!(
            "the demo reported {} of {total} levels",
            levels.len()
        ));
    }
    let stepping = demo::parse_stepping(&text).ok_or_else(|| {
        Failure::new(format!(
            "the log names no stepper (`demo stepping=fixed|events`, {})",
            log_path.display()
        ))
    })?;
    compare_with_sim(&levels, stepping, &mut problems)?;

    // 2. The LEDs, rebuilt from the GPIO trace.
    let trace = std::fs::read(&trace_path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", trace_path.display())))?;
    let trace = String::from_utf8_lossy(&trace);
    let timeline = Timeline::from_lines(trace.lines());
    let frames: Vec<LoggedFrame> = text.lines().filter_map(parse_frame).collect();
    check_frames(&timeline, &frames, levels.len(), &mut problems);

    // 2b. The sensor path ran in the demo: QEMU's TWI stub identified as the
    //     MMA8653FC, its counts in the summary.
    if !text
        .lines()
        .any(|line| line.trim_end().ends_with("accel=mma8653fc"))
    {
        problems.report("the demo did not detect the MMA8653FC (`accel=mma8653fc`)".into());
    }
    match text.lines().find(|line| line.contains("demo sensor: ")) {
        Some(line) => say!("{}", &line[line.find("demo sensor: ").unwrap_or(0)..]),
        None => problems.report("no `demo sensor:` line (re-inits and faults)".into()),
    }

    // 2b'. The watchdog was petted in time all through the demo.
    match parse_watchdog(&text) {
        Some((waited, resets_at)) if waited < resets_at => {
            say!("watchdog: longest wait without a pet {waited} ms (resets at {resets_at} ms)");
        }
        Some((waited, resets_at)) => problems.report(format!(
            "the watchdog went {waited} ms without a pet: a board resets at {resets_at} ms"
        )),
        None => problems.report("no `watchdog: longest wait` line".into()),
    }

    // 2c. Each level's frame costs (a second run: counting stops interrupts).
    check_profile(&tools, &elf, &target, limit, &mut problems)?;

    // 3. Without the demo: play on QEMU's stub accelerometer.
    check_play_on_stub(&tools, &elf, &target, limit, &mut problems)?;

    // 4. Budgets.
    match parse_ram(&text) {
        Some((statics, stack)) => {
            let used = statics + stack;
            let verdict = if used <= ram_budget { "ok" } else { "OVER" };
            say!(
                "RAM: statics {statics} B + stack high-water {stack} B = {used} B of 16384 (budget {ram_budget} B): {verdict}"
            );
            if used > ram_budget {
                problems.report(format!(
                    "RAM {used} B is over the budget of {ram_budget} B by {} B",
                    used - ram_budget
                ));
            }
        }
        None => problems.report("no `ram:` line in the log".into()),
    }
    // 4'. The sensor path on every chip, failed transfers and bus clears
    //     included: QEMU's stub runs only the MMA8653FC's and never fails,
    //     so its stack is bounded from the ELF instead.
    check_sensor_stack(&elf, parse_ram(&text), ram_budget, &mut problems)?;
    match parse_cpu(&text) {
        Some(load) => {
            say!(
                "CPU load {} % of a 16 MHz Cortex-M0 (budget {} %)",
                demo::centi(load),
                demo::centi(cpu_budget)
            );
            if load > cpu_budget {
                problems.report(format!(
                    "CPU load {} % is over the budget of {} %",
                    demo::centi(load),
                    demo::centi(cpu_budget)
                ));
            }
        }
        None => problems.report("no `cpu load:` line in the log".into()),
    }
    let size = crate::size::measure(&elf)?;
    say!(
        "flash: {} B (text {} + data {}) of 262144 (budget {flash_budget} B)",
        size.flash(),
        size.text,
        size.data
    );
    if size.flash() > flash_budget {
        let data = std::fs::read(&elf)
            .map_err(|e| Failure::new(format!("cannot read {}: {e}", elf.display())))?;
        match bloat(&data) {
            Ok(list) => {
                say!("where the code goes (bytes of code symbols by module):");
                for (module, bytes) in list.iter().take(12) {
                    eprintln!("  {bytes:>7}  {module}");
                }
            }
            Err(e) => say!("cannot read the symbols: {e}"),
        }
        problems.report(format!(
            "flash {} B is over the budget of {flash_budget} B by {} B",
            size.flash(),
            size.flash() - flash_budget
        ));
    }

    if !problems.0.is_empty() {
        return Err(Failure::new(format!(
            "FAILED: {} problem(s) (log {}, trace {})",
            problems.0.len(),
            log_path.display(),
            trace_path.display()
        )));
    }
    say!(
        "OK: {} levels won as the simulator plays them, the LEDs show what the game drew, within budgets",
        levels.len()
    );
    Ok(0)
}

/// Prints the static bound of the sensor path's stack
/// ([`crate::stack_bound::sensor_stack`]) beside the high-water the demo
/// measured, and reports a problem when the statics plus the bound would
/// not fit `ram_budget`.
fn check_sensor_stack(
    elf: &Path,
    ram: Option<(u64, u64)>,
    ram_budget: u64,
    problems: &mut Problems,
) -> Result<(), Failure> {
    let data = std::fs::read(elf)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", elf.display())))?;
    let bound = match crate::stack_bound::sensor_stack(&data) {
        Ok(bound) => bound,
        Err(e) => {
            problems.report(format!(
                "no static bound of the sensor path's stack ({}): {e}",
                elf.display()
            ));
            return Ok(());
        }
    };
    let interrupts: Vec<String> = bound
        .interrupts
        .iter()
        .map(|(name, bytes)| format!("{name} {bytes} B"))
        .collect();
    say!(
        "sensor path stack, static bound from the ELF (MMA8653FC, FXOS8700CQ and LSM303AGR branches, failed transfers, bus clears): \
         main to the executor {} B + input task {} B + interrupts ({}) = {} B; {} sensor functions in its calls, {} calls through a register not followed",
        bound.thread_base,
        bound.input_task.bytes,
        interrupts.join(", "),
        bound.total(),
        bound.covers.len(),
        bound.input_task.indirect
    );
    let short: Vec<&str> = bound
        .deepest_path
        .iter()
        .map(|name| {
            let name = name.trim_end_matches("::{{closure}}");
            name.rsplit("::").next().unwrap_or(name)
        })
        .collect();
    say!("sensor path stack, its deepest path: {}", short.join(" > "));
    if let Some((statics, measured)) = ram {
        let verdict = if bound.total() <= measured {
            "within the measured high-water"
        } else {
            "above the measured high-water"
        };
        say!(
            "sensor path stack: bound {} B vs measured high-water {measured} B (the game's path on QEMU's stub): {verdict}",
            bound.total()
        );
        if statics + bound.total() > ram_budget {
            problems.report(format!(
                "RAM on the sensor path: statics {statics} B + stack bound {} B is over the budget of {ram_budget} B",
                bound.total()
            ));
        }
    }
    Ok(())
}

/// The fault picture the game shows while the sensor is down (a cross from
/// corner to corner, `render::screens::fault_frame`), full brightness.
pub const FAULT_CROSS: [[u8; leds::SIZE]; leds::SIZE] = [
    [15, 0, 0, 0, 15],
    [0, 15, 0, 15, 0],
    [0, 0, 15, 0, 0],
    [0, 15, 0, 15, 0],
    [15, 0, 0, 0, 15],
];

/// Plays (no demo) for two seconds in QEMU: the firmware must find the
/// MMA8653FC through the TWI stub (`accel=mma8653fc`), keep polling whatever
/// its data registers return without a panic (the plausibility rules decide
/// whether the sensor stays up), and the LEDs (from the GPIO trace, over the
/// second second) must show the picture that decision implies: the maze
/// with the sensor up, the fault cross with it down.
fn check_play_on_stub(
    tools: &setup::Qemu,
    elf: &Path,
    target: &Path,
    limit: Duration,
    problems: &mut Problems,
) -> Result<(), Failure> {
    let log_path = target.join("check-microbit-v1-sensor.log");
    let trace_path = target.join("check-microbit-v1-sensor.trace");
    let file = File::create(&log_path)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", log_path.display())))?;
    say!("playing 2 s in QEMU on its TWI stub (the MMA8653FC's identity, no chip behind it)…");
    let args = ["--seconds=2".to_string(), "--no-frame-log".to_string()];
    let (status, _) = qemu_run(
        tools,
        elf,
        &args,
        Some(&trace_path),
        Sink::File(&file),
        limit,
    )?;
    let text = std::fs::read(&log_path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", log_path.display())))?;
    let text = demo::strip_colours(&String::from_utf8_lossy(&text));
    let _ = std::fs::write(&log_path, &text);
    let trace = std::fs::read(&trace_path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", trace_path.display())))?;
    let timeline = Timeline::from_lines(String::from_utf8_lossy(&trace).lines());
    let seen = timeline.perceived(1_000_000, 2_000_000);
    let detected = text
        .lines()
        .any(|line| line.trim_end().ends_with("accel=mma8653fc"));
    let stop = text.lines().find(|line| line.contains("stop after 2 s"));
    let down = stop.map(|line| line.contains("sensor down: true"));
    let shown_ok = match down {
        Some(true) => seen == FAULT_CROSS,
        Some(false) => seen != FAULT_CROSS && seen.iter().flatten().any(|&level| level > 0),
        None => false,
    };
    if status != 0 || !detected || !shown_ok {
        problems.report(format!(
            "play on the stub: status {status}, accel=mma8653fc: {detected}, sensor down: {down:?}, \
             LEDs {} (the cross is {}); log {}",
            hex_rows(&seen),
            hex_rows(&FAULT_CROSS),
            log_path.display()
        ));
    } else {
        say!(
            "play on the stub: MMA8653FC found, sensor down: {}, the LEDs show {}",
            down == Some(true),
            if down == Some(true) {
                "the fault cross"
            } else {
                "the game"
            }
        );
    }
    Ok(())
}

/// `watchdog: longest wait without a pet W ms (it resets at R ms)` → (W, R).
pub fn parse_watchdog(log: &str) -> Option<(u64, u64)> {
    log.lines().find_map(|line| {
        let rest = &line
            [line.find("longest wait without a pet ")? + "longest wait without a pet ".len()..];
        let (waited, rest) = rest.split_once(" ms (it resets at ")?;
        let (resets_at, _) = rest.split_once(" ms")?;
        Some((waited.parse().ok()?, resets_at.parse().ok()?))
    })
}

/// `profile LEVEL: N frames, instructions per frame: physics AVG (max MAX),
/// …` → (level, frames, average, max).
pub fn parse_profile(line: &str) -> Option<(String, u32, u64, u64)> {
    let rest = &line[line.find("profile ")? + "profile ".len()..];
    let (level, rest) = rest.split_once(": ")?;
    let (frames, rest) = rest.split_once(" frames, instructions per frame: physics ")?;
    let (average, rest) = rest.split_once(" (max ")?;
    let (max, _) = rest.split_once(')')?;
    Some((
        level.to_string(),
        frames.parse().ok()?,
        average.parse().ok()?,
        max.parse().ok()?,
    ))
}

/// The worst frame the lead's physics work is to bring under (issue 27), M0
/// instructions: reported, not yet enforced.
const WORST_FRAME_GOAL: u64 = 60_000;

/// Runs `--demo --profile` and prints each level's frame costs; it must
/// still win every level and profile each.
fn check_profile(
    tools: &setup::Qemu,
    elf: &Path,
    target: &Path,
    limit: Duration,
    problems: &mut Problems,
) -> Result<(), Failure> {
    let log_path = target.join("check-microbit-v1-profile.log");
    let file = File::create(&log_path)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", log_path.display())))?;
    say!("profiling the demo's frames in QEMU microbit (--demo --profile)…");
    let args = [
        "--demo".to_string(),
        "--profile".to_string(),
        "--no-frame-log".to_string(),
    ];
    let (status, _) = qemu_run(tools, elf, &args, None, Sink::File(&file), limit)?;
    let text = std::fs::read(&log_path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", log_path.display())))?;
    let text = demo::strip_colours(&String::from_utf8_lossy(&text));
    let _ = std::fs::write(&log_path, &text);
    let profiles: Vec<_> = text.lines().filter_map(parse_profile).collect();
    let (levels, _) = demo::parse_levels(&text);
    if status != 0 || profiles.is_empty() || profiles.len() != levels.len() {
        problems.report(format!(
            "profile run: status {status}, {} profiles for {} levels (log {})",
            profiles.len(),
            levels.len(),
            log_path.display()
        ));
    }
    for (level, frames, average, max) in &profiles {
        let over = if *max > WORST_FRAME_GOAL {
            " (over the 60 000 goal)"
        } else {
            ""
        };
        say!("profile {level}: {frames} frames, physics {average} per frame, worst {max}{over}");
    }
    Ok(())
}

/// Compares each level with `sim --level NAME --autopilot --json --stepping S`.
fn compare_with_sim(
    levels: &[Level],
    stepping: &str,
    problems: &mut Problems,
) -> Result<(), Failure> {
    let sim = demo::build_sim()?;
    for (level, verdict) in demo::compare_levels(&sim, levels, stepping, "v1") {
        problems.report(format!("level {level}: {verdict:?}"));
    }
    Ok(())
}

/// Checks the logged frames against the trace (see the module doc).
fn check_frames(
    timeline: &Timeline,
    frames: &[LoggedFrame],
    levels: usize,
    problems: &mut Problems,
) {
    if timeline.is_empty() {
        problems.report("the GPIO trace has no pin changes".into());
        return;
    }
    let mut maze_frames = vec![0usize; levels];
    let mut worst = 0u8;
    for frame in frames {
        let seen = timeline.perceived(frame.t0, frame.t1);
        let difference = max_difference(&seen, &frame.rows);
        worst = worst.max(difference);
        if difference > FRAME_TOLERANCE {
            problems.report(format!(
                "level {}: the LEDs showed {} over [{}, {}) µs, the game drew {}",
                usize::from(frame.level) + 1,
                hex_rows(&seen),
                frame.t0,
                frame.t1,
                hex_rows(&frame.rows)
            ));
        } else if frame.shows_the_maze() {
            if let Some(count) = maze_frames.get_mut(usize::from(frame.level)) {
                *count += 1;
            }
        }
    }
    say!(
        "display: {} frames rebuilt from {} GPIO level changes, largest difference {worst} level(s); maze frames per level {maze_frames:?}",
        frames.len(),
        timeline.len()
    );
    for (level, &count) in maze_frames.iter().enumerate() {
        if count == 0 {
            problems.report(format!(
                "level {}: no frame showing the maze was matched on the LEDs",
                level + 1
            ));
        }
    }
}

#[cfg(test)]
mod tests;
