//! `cargo xtask check-demo`: the firmware must play exactly like the host
//! simulator. The QEMU firmware's headless demo (the autopilot plays every
//! built-in level, then three generated mazes) logs, per level,
//!
//! ```text
//! demo <n>/<total> level=<name> outcome=<won|fell|timeout> steps=<physics steps> state_hash=<16 hex>
//! ```
//!
//! and `sim --level <name> --autopilot --json` (for a generated maze, named
//! `maze-SEED-NxNxS-dD`: `sim --generate SEED --size N --storeys S
//! --difficulty D …`, [`sim::level_args`]) must report the same outcome, step
//! count and state hash; every level must be won. The demo's CPU load must
//! stay within CPU_BUDGET_CENTIPERCENT (default 300: 3.00 % of a 64 MHz
//! Cortex-M4). Under -icount that count is exact and the same on every machine,
//! so the budget is a report with a limit, like the flash budget, not a timing
//! test.

mod ghosts;
mod log;
mod sim;

use std::path::Path;

pub use ghosts::check_ghosts;
pub use log::{centi, create_log, parse_cpu_load, parse_levels, parse_stepping, read_log, Level};
pub use sim::{build_sim, compare_levels, simulate, verdict, Verdict};

use crate::boards::{Board, QEMU};
use crate::error::{say, Failure, Outcome};
use crate::runner::{self, Output};
use crate::workspace;
pub use log::{parse_budget_cuts, parse_worst_frames};

/// The worst physics frame of each level, top-difficulty maze and stress scene
/// (`game::stress`: every `profile` line but the total) against `bound`
/// instructions (`what`: the board's CPU): a frame over it is a problem.
fn check_worst_frames(log: &str, bound: u64, what: &str, problems: &mut Problems) {
    let frames = parse_worst_frames(log);
    if frames.is_empty() {
        problems.report("no `profile` lines in the demo log".to_string());
    }
    for (name, max) in frames {
        if max > bound {
            problems.report(format!(
                "{name}: worst physics frame {max} {what} instructions, over the bound of {bound}"
            ));
        } else {
            say!("{name}: worst physics frame {max} {what} instructions");
        }
    }
}

/// What every board's profile plays beside the levels, by the name its
/// `profile` and `budget` lines give (`app::profile_scenes`): the
/// top-difficulty mazes (`game::stress::HARD_MAZES`, named as
/// `game::generate` names a maze), then the stress scenes.
pub fn profiled_scenes() -> Vec<String> {
    use marble_rolling::game::stress::{HARD_MAZES, STRESS};
    let mazes = HARD_MAZES.iter().map(|m| m.to_string());
    let scenes = STRESS.iter().map(|s| s.level.info.name.to_string());
    mazes.chain(scenes).collect()
}

/// Reports each of [`profiled_scenes`] that has no `profile` line or no
/// `budget` line in `log`: a scene the board could not set up, or a profile
/// cut short.
pub fn check_scenes_logged(log: &str, problems: &mut Problems) {
    let frames = parse_worst_frames(log);
    let cuts = parse_budget_cuts(log);
    for name in profiled_scenes() {
        let profiled = frames.iter().any(|(n, _)| *n == name);
        let cut = cuts.iter().any(|(n, _)| *n == name);
        if !profiled || !cut {
            problems.report(format!(
                "scene {name}: no `profile {name}:` or `budget {name}:` line in the log"
            ));
        }
    }
}

/// The flight budget (`physics::world::FLIGHT_BUDGET`) is for the scenes built to
/// reach it: a built-in level it cuts is a problem; the stress scenes and the
/// top-difficulty mazes are reported.
fn check_budget_cuts(log: &str, levels: &[String], problems: &mut Problems) {
    let cuts = parse_budget_cuts(log);
    if cuts.is_empty() {
        problems.report("no `budget` lines in the demo log".to_string());
    }
    for (name, cuts) in cuts {
        if cuts > 0 && levels.contains(&name) {
            problems.report(format!(
                "{name}: the flight budget cut {cuts} marble-steps (a built-in level must never reach it)"
            ));
        } else {
            say!("{name}: the flight budget cut {cuts} marble-steps");
        }
    }
}

/// What failed, in every board's check: each problem is reported when found,
/// and the check goes on so that one run shows them all.
#[derive(Default)]
pub struct Problems(u32);

impl Problems {
    pub fn report(&mut self, message: String) {
        say!("{message}");
        self.0 += 1;
    }

    pub fn count(&self) -> u32 {
        self.0
    }
}

/// `cargo xtask check-demo`.
pub fn run() -> Outcome {
    let log = workspace::env_path(
        "CHECK_DEMO_LOG",
        workspace::target_dir()?.join("check-demo-qemu.log"),
    );
    let mut problems = Problems::default();

    say!("running the QEMU demo (cargo qemu --demo)…");
    let status = run_demo(&QEMU, &log, &["--demo"])?;
    let text = read_log(&log)?;
    if status != 0 {
        problems.report(format!(
            "the QEMU demo exited with status {status} (log: {}); its last lines:",
            log.display()
        ));
        let lines: Vec<&str> = text.lines().collect();
        for line in &lines[lines.len().saturating_sub(15)..] {
            eprintln!("{line}");
        }
    }

    let levels = check_levels(&QEMU, &text, &log, &mut problems)?;

    let budget = QEMU.budget(&QEMU.budgets.cpu)?;
    match parse_cpu_load(&text) {
        None => problems.report(format!("no cpu load line in the QEMU log ({})", log.display())),
        Some(load) if load > budget => problems.report(format!(
            "CPU load {} % is over the budget of {} % (cargo xtask qemu-profile shows where it goes)",
            centi(load),
            centi(budget)
        )),
        Some(load) => say!("CPU load {} % of 64 MHz (budget {} %)", centi(load), centi(budget)),
    }

    let bound = QEMU.budget(&QEMU.budgets.frame)?;
    let names: Vec<String> = levels.iter().map(|l| l.name.clone()).collect();
    check_worst_frames(&text, bound, QEMU.core, &mut problems);
    check_budget_cuts(&text, &names, &mut problems);
    check_scenes_logged(&text, &mut problems);

    if problems.count() > 0 {
        return Err(Failure::new(format!(
            "FAILED (QEMU log: {})",
            log.display()
        )));
    }
    say!(
        "OK: {} levels won, QEMU and the simulator agree on outcome, steps and state hash",
        levels.len()
    );
    Ok(0)
}

/// The levels of `board`'s demo log (`text`, from `log`), each compared with
/// the simulator's run (`sim --level NAME --autopilot --json --stepping S`,
/// [`compare_levels`]): a level that differs, or a count short of the
/// demo's total, is a problem; a log without levels or without its stepper
/// is a failure.
pub fn check_levels(
    board: &Board,
    text: &str,
    log: &Path,
    problems: &mut Problems,
) -> Result<Vec<Level>, Failure> {
    let (levels, total) = parse_levels(text);
    if levels.is_empty() {
        return Err(Failure::new(format!(
            "no per-level lines in the {} demo's log ({})",
            board.name,
            log.display()
        )));
    }
    if let Some(total) = total.filter(|&total| total != levels.len()) {
        problems.report(format!(
            "the {} demo reported {} of {total} levels",
            board.name,
            levels.len()
        ));
    }
    let stepping = parse_stepping(text).ok_or_else(|| {
        Failure::new(format!(
            "the {} demo's log names no stepper (`demo stepping=fixed|events`, {})",
            board.name,
            log.display()
        ))
    })?;
    let sim = build_sim()?;
    for (level, verdict) in compare_levels(&sim, &levels, stepping, board.tag) {
        problems.report(format!("level {level}: {verdict:?}"));
    }
    Ok(levels)
}

/// `board`'s headless demo, exactly as `cargo xtask qemu --demo` runs it, its
/// output (QEMU's and defmt-print's) into `log`; QEMU's status.
fn run_demo(board: &Board, log: &Path, args: &[&str]) -> Outcome {
    let file = create_log(log)?;
    let machine = board.machine()?;
    let limit = runner::timeout(board.game.timeout)?;
    let tools = board.game.qemu_tools()?;
    let elf = board.game.build()?;
    let demo: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    let output = Output::File(&file);
    match runner::headless(machine, &board.game, &tools, &elf, &demo, output, limit) {
        Ok(status) => Ok(status),
        // A timeout is a failed demo like any other: report it with the log.
        Err(failure) if failure.status == 124 => Ok(124),
        Err(failure) => Err(failure),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worst_frames_come_from_every_profile_line_but_the_total() {
        let log = "\
34.4 INFO  profile first-roll: 73 frames, instructions per frame: physics 1722 (max 1934), autopilot 2261, render 1532
38.7 INFO  profile all levels: 2981 frames, instructions per frame: physics 3926 (max 65765), autopilot 2741, render 1727
38.8 INFO  profile drop-onto-marble: 384 frames, instructions per frame: physics 900 (max 30123), autopilot 0, render 0
INFO  demo summary: 13/13 levels won
";
        assert_eq!(
            parse_worst_frames(log),
            [
                ("first-roll".to_string(), 1934),
                ("drop-onto-marble".to_string(), 30123)
            ]
        );
        let mut problems = Problems::default();
        check_worst_frames(log, 1_900, "M4", &mut problems);
        assert!(problems.count() > 0, "a level's 1 934 is over 1 900");
        let mut problems = Problems::default();
        check_worst_frames(log, 30_000, "M4", &mut problems);
        assert!(
            problems.count() > 0,
            "a stress scene's 30 123 is over 30 000, as a level's would be"
        );
        let mut problems = Problems::default();
        check_worst_frames(log, 30_123, "M4", &mut problems);
        assert!(problems.count() == 0, "a frame at the bound is within it");
        let mut problems = Problems::default();
        check_worst_frames("no profile here", 64_000, "M4", &mut problems);
        assert!(problems.count() > 0, "a log without profiles is a problem");
    }

    #[test]
    fn a_budget_cut_on_a_built_in_level_is_a_problem() {
        let log = "\
34.5 INFO  budget first-roll: 0 marble-steps cut
38.9 INFO  budget drop-onto-marble: 42 marble-steps cut
";
        assert_eq!(
            parse_budget_cuts(log),
            [
                ("first-roll".to_string(), 0),
                ("drop-onto-marble".to_string(), 42)
            ]
        );
        let mut problems = Problems::default();
        check_budget_cuts(log, &["first-roll".to_string()], &mut problems);
        assert!(
            problems.count() == 0,
            "cuts in a stress scene are reported only"
        );
        let mut problems = Problems::default();
        check_budget_cuts(log, &["drop-onto-marble".to_string()], &mut problems);
        assert!(problems.count() > 0, "a cut on a level is a problem");
        let mut problems = Problems::default();
        check_budget_cuts("no budget here", &[], &mut problems);
        assert!(
            problems.count() > 0,
            "a log without budget lines is a problem"
        );
    }

    #[test]
    fn every_profiled_scene_must_have_its_lines() {
        let names = profiled_scenes();
        assert_eq!(
            names,
            [
                "maze-1-7x7x2-d9",
                "maze-2-7x7x2-d9",
                "maze-3-7x7x2-d9",
                "rattle-corner",
                "four-shaken",
                "drop-onto-marble",
                "long-fall"
            ]
        );
        let whole: String = names
            .iter()
            .map(|name| {
                format!(
                    "INFO  profile {name}: 512 frames, instructions per frame: physics 900 (max 30123), autopilot 0, render 0\n\
                     INFO  budget {name}: 0 marble-steps cut\n"
                )
            })
            .collect();
        let mut problems = Problems::default();
        check_scenes_logged(&whole, &mut problems);
        assert_eq!(problems.count(), 0, "every scene logged");
        // The problems reported for the log without the lines holding `gone`.
        let problems_without = |gone: &str| {
            let log: String = whole
                .lines()
                .filter(|line| !line.contains(gone))
                .map(|line| format!("{line}\n"))
                .collect();
            let mut problems = Problems::default();
            check_scenes_logged(&log, &mut problems);
            problems.count()
        };
        assert_eq!(
            problems_without("budget long-fall:"),
            1,
            "long-fall's budget line is missing"
        );
        assert_eq!(
            problems_without("profile maze-2-"),
            1,
            "a maze's profile line is missing"
        );
    }
}
