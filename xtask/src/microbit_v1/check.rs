//! `cargo xtask check-microbit-v1` (see the parent module's doc).

use std::path::Path;
use std::time::Duration;

use super::log::{bloat, parse_profile, parse_ram, parse_watchdog};
use super::qemu::{qemu_run, Sink};
use super::{hex_rows, leds, max_difference, parse_frame, LoggedFrame, Timeline};
use crate::boards::MICROBIT_V1;
use crate::demo::{self, Problems};
use crate::error::{say, Failure, Outcome};
use crate::runner;
use crate::setup;
use crate::workspace;

/// Tolerance of the rebuilt frames, brightness levels per pixel.
const FRAME_TOLERANCE: u8 = 1;

/// `cargo xtask check-microbit-v1`: see the module doc.
pub fn check() -> Outcome {
    let target = workspace::target_dir()?;
    let log_path = workspace::env_path("CHECK_V1_LOG", target.join("check-microbit-v1.log"));
    let trace_path = workspace::env_path("CHECK_V1_TRACE", target.join("check-microbit-v1.trace"));
    let board = &MICROBIT_V1;
    let ram_budget = board.budget(&board.budgets.ram)?;
    let flash_budget = board.budget(&board.budgets.flash)?;
    let cpu_budget = board.budget(&board.budgets.cpu)?;
    let frame_goal = board.budget(&board.budgets.frame)?;
    let limit = runner::timeout(board.game.timeout)?;
    let mut problems = Problems::default();

    let tools = board.game.qemu_tools()?;
    // The profile's image first: the plain one, built last, is what cargo's
    // output path then holds (and what a board is flashed with).
    let profiled = board.game.build_profiled()?;
    let elf = board.game.build()?;
    let file = demo::create_log(&log_path)?;
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
    let text = demo::read_log(&log_path)?;
    say!("QEMU ran for {:.1} s of host time", took.as_secs_f64());
    if status != 0 {
        problems.report(format!(
            "the demo exited with status {status} (log: {})",
            log_path.display()
        ));
    }

    // 1. Every level as the simulator plays it.
    let levels = demo::check_levels(board, &text, &log_path, &mut problems)?;

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
    check_profile(
        &tools,
        &profiled,
        &target,
        (limit, frame_goal),
        &mut problems,
    )?;

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
    match demo::parse_cpu_load(&text) {
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

    if problems.count() > 0 {
        return Err(Failure::new(format!(
            "FAILED: {} problem(s) (log {}, trace {})",
            problems.count(),
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
    let file = demo::create_log(&log_path)?;
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
    let text = demo::read_log(&log_path)?;
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

/// Runs `--demo --profile` and prints each level's frame costs, then those of
/// the top-difficulty mazes and the stress scenes (`app::profile_scenes`),
/// each worst frame against `goal` (the board's frame budget, M0
/// instructions, enforced on every one of them);
/// it must still win every level and profile each, and log every scene's
/// `profile` and `budget` lines.
fn check_profile(
    tools: &setup::Qemu,
    elf: &Path,
    target: &Path,
    (limit, goal): (Duration, u64),
    problems: &mut Problems,
) -> Result<(), Failure> {
    let log_path = target.join("check-microbit-v1-profile.log");
    let file = demo::create_log(&log_path)?;
    say!("profiling the demo's frames in QEMU microbit (--demo --profile)…");
    let args = [
        "--demo".to_string(),
        "--profile".to_string(),
        "--no-frame-log".to_string(),
    ];
    let (status, _) = qemu_run(tools, elf, &args, None, Sink::File(&file), limit)?;
    let text = demo::read_log(&log_path)?;
    let profiles: Vec<_> = text.lines().filter_map(parse_profile).collect();
    let (levels, _) = demo::parse_levels(&text);
    let scenes = demo::profiled_scenes();
    let level_profiles = profiles
        .iter()
        .filter(|(name, ..)| !scenes.contains(name))
        .count();
    if status != 0 || level_profiles == 0 || level_profiles != levels.len() {
        problems.report(format!(
            "profile run: status {status}, {level_profiles} profiles for {} levels (log {})",
            levels.len(),
            log_path.display()
        ));
    }
    demo::check_scenes_logged(&text, problems);
    let cuts = demo::parse_budget_cuts(&text);
    for (name, frames, average, max) in &profiles {
        let scene = scenes.contains(name);
        let what = if scene { "scene " } else { "" };
        let cut = match cuts.iter().find(|(n, _)| n == name) {
            Some((_, cut)) if scene => format!(", flight budget cut {cut} marble-steps"),
            _ => String::new(),
        };
        let line = format!(
            "profile {what}{name}: {frames} frames, physics {average} per frame, worst {max}"
        );
        if *max > goal {
            problems.report(format!(
                "{line}{cut}: over the bound of {} M0 instructions",
                grouped(goal)
            ));
        } else {
            say!("{line}{cut}");
        }
    }
    if let Some((statics, stack)) = parse_ram(&text) {
        say!(
            "RAM in the profile run (the scenes' players on the stack): statics {statics} B + stack high-water {stack} B = {} B",
            statics + stack
        );
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

/// `n` with its digits in groups of three ("60 000"), as the messages write
/// figures.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, digit) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(digit);
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn figures_are_grouped_by_three() {
        assert_eq!(super::grouped(60_000), "60 000");
        assert_eq!(super::grouped(1_234_567), "1 234 567");
        assert_eq!(super::grouped(999), "999");
        assert_eq!(super::grouped(0), "0");
    }
}
