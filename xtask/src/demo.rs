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
//! --difficulty D …`, [`level_args`]) must report the same outcome, step
//! count and state hash; every level must be won. The demo's CPU load must
//! stay within CPU_BUDGET_CENTIPERCENT (default 300: 3.00 % of a 64 MHz
//! Cortex-M4). Under -icount that count is exact and the same on every machine,
//! so the budget is a report with a limit, like the flash budget, not a timing
//! test.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::error::{say, Failure, Outcome};
use crate::firmware::{self, Artifact};
use crate::runner::{self, Output};
use crate::setup::{self, M4};
use crate::workspace;

/// One level as the firmware reported it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level {
    pub name: String,
    pub outcome: String,
    pub steps: String,
    pub hash: String,
}

/// The simulator's `--json` fields we compare (absent ones are `None`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Sim {
    pub outcome: Option<String>,
    pub steps: Option<String>,
    pub hash: Option<String>,
}

/// One row's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    Ok,
    SimFailed,
    NotWon,
    Mismatch,
}

impl Verdict {
    fn text(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::SimFailed => "SIM FAILED",
            Verdict::NotWon => "NOT WON",
            Verdict::Mismatch => "MISMATCH",
        }
    }
}

/// `text` without ANSI colour sequences (`ESC [ digits/semicolons m`), should
/// defmt-print or cargo add any.
pub fn strip_colours(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("\x1b[") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        let params = after.len()
            - after
                .trim_start_matches(|c: char| c.is_ascii_digit() || c == ';')
                .len();
        if after[params..].starts_with('m') {
            rest = &after[params + 1..];
        } else {
            out.push('\x1b');
            rest = &rest[at + 1..];
        }
    }
    out.push_str(rest);
    out
}

/// The per-level lines, in playing order, and the total the first one names.
pub fn parse_levels(log: &str) -> (Vec<Level>, Option<usize>) {
    let mut levels = Vec::new();
    let mut total = None;
    let mut total_seen = false;
    for line in log.lines() {
        if !total_seen {
            if let Some(found) = rightmost(line, "demo ", parse_total) {
                total_seen = true;
                total = found.parse().ok();
            }
        }
        if let Some(level) = rightmost(line, "demo ", parse_level) {
            levels.push(level);
        }
    }
    (levels, total)
}

/// The stepper the demo ran (`demo stepping=<fixed|events>`, logged before the
/// first level), which the simulator must use too.
pub fn parse_stepping(log: &str) -> Option<&str> {
    log.lines().find_map(|line| {
        let (_, rest) = line.rsplit_once("demo stepping=")?;
        let mode = rest.split_whitespace().next()?;
        matches!(mode, "fixed" | "events").then_some(mode)
    })
}

/// The rightmost occurrence of `marker` in `line` from which `parse` succeeds
/// (what a sed pattern led by a greedy `.*` matches).
fn rightmost<T>(line: &str, marker: &str, parse: impl Fn(&str) -> Option<T>) -> Option<T> {
    line.rmatch_indices(marker)
        .find_map(|(at, _)| parse(&line[at + marker.len()..]))
}

/// `<digits>/<digits> level=` → the total (possibly empty), after `demo `.
fn parse_total(rest: &str) -> Option<String> {
    let rest = rest
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .strip_prefix('/')?;
    let total = digits(rest);
    rest[total.len()..]
        .starts_with(" level=")
        .then(|| total.to_string())
}

/// `<n>/<total> level=<name> outcome=<o> steps=<s> state_hash=<hex>`, after `demo `.
fn parse_level(rest: &str) -> Option<Level> {
    let rest = rest
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .strip_prefix('/')?;
    let rest = rest
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .strip_prefix(" level=")?;
    let (name, rest) = rest.split_once(' ')?;
    let rest = rest.strip_prefix("outcome=")?;
    let (outcome, rest) = rest.split_once(' ')?;
    let rest = rest.strip_prefix("steps=")?;
    let steps = digits(rest);
    let rest = rest[steps.len()..].strip_prefix(" state_hash=")?;
    let hash = rest
        .split(|c: char| !c.is_ascii_hexdigit())
        .next()
        .unwrap_or_default();
    Some(Level {
        name: name.into(),
        outcome: outcome.into(),
        steps: steps.into(),
        hash: hash.into(),
    })
}

fn digits(text: &str) -> &str {
    let end = text
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(text.len());
    &text[..end]
}

/// The CPU load in hundredths of a percent, from the first line like
/// `cpu load: … = X.YY % of a 64 MHz …`.
pub fn parse_cpu_load(log: &str) -> Option<u64> {
    log.lines().find_map(cpu_load_of)
}

fn cpu_load_of(line: &str) -> Option<u64> {
    let start = line.find("cpu load: ")? + "cpu load: ".len();
    let line = &line[start..];
    line.rmatch_indices(" % of a 64 MHz").find_map(|(end, _)| {
        let number = &line[..end];
        let cents = number.get(number.len().checked_sub(2)?..)?;
        let before = number[..number.len() - 2].strip_suffix('.')?;
        let head = before.trim_end_matches(|c: char| c.is_ascii_digit());
        let whole = &before[head.len()..];
        if !head.ends_with(" = ") || !cents.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        format!("{whole}{cents}").parse().ok()
    })
}

/// Every `profile NAME: N frames, instructions per frame: physics AVG (max MAX)`
/// line of a demo log (a level's or a stress scene's; `all levels` left out, it
/// repeats the levels' worst): the name and its worst physics frame.
pub fn parse_worst_frames(log: &str) -> Vec<(String, u64)> {
    log.lines()
        .filter_map(|line| {
            let rest = &line[line.find("profile ")? + "profile ".len()..];
            let (name, rest) = rest.split_once(": ")?;
            let max = rest.split_once("physics ")?.1.split_once("(max ")?.1;
            let max = max.split_once(')')?.0.parse().ok()?;
            (name != "all levels").then(|| (name.to_string(), max))
        })
        .collect()
}

/// The worst physics frame of each level against `bound` instructions (`what`:
/// the board's CPU): a level's frame over it is a problem. The stress scenes
/// (`game::stress`) and the top-difficulty mazes (every other `profile` line)
/// are measured and reported against the same bound, but not yet enforced: with
/// the flight budget they take up to 1.4 times it (docs/performance.md has the
/// figures).
fn check_worst_frames(
    log: &str,
    levels: &[String],
    bound: u64,
    what: &str,
    problems: &mut Problems,
) {
    let frames = parse_worst_frames(log);
    if frames.is_empty() {
        problems.report("no `profile` lines in the demo log".to_string());
    }
    for (name, max) in frames {
        let level = levels.contains(&name);
        match (max > bound, level) {
            (true, true) => problems.report(format!(
                "{name}: worst physics frame {max} {what} instructions, over the bound of {bound}"
            )),
            (true, false) => say!(
                "scene {name}: worst physics frame {max} {what} instructions, over the bound of {bound} (reported, not enforced yet)"
            ),
            (false, _) => say!("{name}: worst physics frame {max} {what} instructions"),
        }
    }
}

/// Every `budget NAME: N marble-steps cut` line of a demo log: the name and how
/// often the step's flight budget cut a marble's step there.
pub fn parse_budget_cuts(log: &str) -> Vec<(String, u64)> {
    log.lines()
        .filter_map(|line| {
            let rest = &line[line.find("budget ")? + "budget ".len()..];
            let (name, rest) = rest.split_once(": ")?;
            let cuts = rest.split_once(" marble-steps cut")?.0.parse().ok()?;
            Some((name.to_string(), cuts))
        })
        .collect()
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

/// The simulator's fields from its output (its last line that starts with `{`).
pub fn parse_sim(stdout: &str) -> Option<Sim> {
    let line = stdout.lines().rfind(|line| line.starts_with('{'))?;
    let json: serde_json::Value = serde_json::from_str(line).ok()?;
    let field = |name: &str| match &json[name] {
        serde_json::Value::String(text) => Some(text.clone()),
        serde_json::Value::Number(number) => Some(number.to_string()),
        serde_json::Value::Bool(flag) => Some(flag.to_string()),
        _ => None,
    };
    Some(Sim {
        outcome: field("outcome"),
        steps: field("steps"),
        hash: field("state_hash"),
    })
}

/// How the firmware's result for a level compares with the simulator's.
pub fn verdict(qemu: &Level, sim: Option<&Sim>) -> Verdict {
    let Some(sim) = sim else {
        return Verdict::SimFailed;
    };
    if qemu.outcome != "won" {
        return Verdict::NotWon;
    }
    let same = sim.outcome.as_deref() == Some(qemu.outcome.as_str())
        && sim.steps.as_deref() == Some(qemu.steps.as_str())
        && sim
            .hash
            .as_ref()
            .is_some_and(|hash| hash.eq_ignore_ascii_case(&qemu.hash));
    if same {
        Verdict::Ok
    } else {
        Verdict::Mismatch
    }
}

/// One table row, each column padded to its width.
pub fn row(cells: [&str; 8]) -> String {
    let [name, q, s, qs, ss, qh, sh, result] = cells;
    format!("{name:<16} {q:<8} {s:<8} {qs:>8} {ss:>8} {qh:<16} {sh:<16} {result}")
}

/// Hundredths as `X.YY`.
pub fn centi(value: u64) -> String {
    format!("{}.{:02}", value / 100, value % 100)
}

/// Whether anything failed; each problem is reported when found, and the check
/// goes on so that one run shows them all.
#[derive(Default)]
struct Problems(bool);

impl Problems {
    fn report(&mut self, message: String) {
        say!("{message}");
        self.0 = true;
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
    let status = run_demo(&log, &["--demo"])?;
    let text = std::fs::read(&log)
        .map_err(|e| Failure::new(format!("cannot read the QEMU log {}: {e}", log.display())))?;
    let text = strip_colours(&String::from_utf8_lossy(&text));
    // The log is kept for reading, as plain text.
    let _ = std::fs::write(&log, &text);
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

    let (levels, total) = parse_levels(&text);
    if levels.is_empty() {
        return Err(Failure::new(format!(
            "no per-level lines in the QEMU log ({})",
            log.display()
        )));
    }
    let stepping = parse_stepping(&text).ok_or_else(|| {
        Failure::new(format!(
            "the QEMU log names no stepper (`demo stepping=fixed|events`, {})",
            log.display()
        ))
    })?;
    if let Some(total) = total.filter(|&total| total != levels.len()) {
        problems.report(format!(
            "the QEMU demo reported {} of {total} levels",
            levels.len()
        ));
    }

    let sim = build_sim()?;
    let failed = compare_levels(&sim, &levels, stepping, "qemu");
    problems.0 |= !failed.is_empty();

    let budget = workspace::env_number("CPU_BUDGET_CENTIPERCENT", 300)?;
    match parse_cpu_load(&text) {
        None => problems.report(format!("no cpu load line in the QEMU log ({})", log.display())),
        Some(load) if load > budget => problems.report(format!(
            "CPU load {} % is over the budget of {} % (cargo xtask qemu-profile shows where it goes)",
            centi(load),
            centi(budget)
        )),
        Some(load) => say!("CPU load {} % of 64 MHz (budget {} %)", centi(load), centi(budget)),
    }

    let bound = workspace::env_number("WORST_FRAME_M4", 64_000)?;
    let names: Vec<String> = levels.iter().map(|l| l.name.clone()).collect();
    check_worst_frames(&text, &names, bound, "M4", &mut problems);
    check_budget_cuts(&text, &names, &mut problems);

    if problems.0 {
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

/// The QEMU board's ghosts' flash image (its host file).
const GHOSTS_IMAGE: &str = "qemu-ghosts.bin";

/// `cargo xtask check-ghosts`: QEMU keeps a ghost across a restart of the
/// demo. On a fresh flash image `--demo --ghosts` runs twice: the first run
/// keeps the autopilot's wins as ghosts (one too long for the buffer is
/// logged, not kept), the second reads each back, races it beside the
/// autopilot and must reach its end on the state hash the level ends on.
pub fn check_ghosts() -> Outcome {
    let target = workspace::target_dir()?;
    let image = target.join(GHOSTS_IMAGE);
    if image.exists() {
        std::fs::remove_file(&image)
            .map_err(|e| Failure::new(format!("cannot remove {}: {e}", image.display())))?;
    }
    let mut logs = Vec::new();
    for run in 1..=2 {
        let log = target.join(format!("check-ghosts-{run}.log"));
        say!("ghosts run {run}: cargo qemu -- --demo --ghosts…");
        let status = run_demo(&log, &["--demo", "--ghosts"])?;
        let text = std::fs::read(&log)
            .map_err(|e| Failure::new(format!("cannot read {}: {e}", log.display())))?;
        let text = strip_colours(&String::from_utf8_lossy(&text));
        if status != 0 {
            return Err(Failure::new(format!(
                "the QEMU demo exited with status {status} (log: {})",
                log.display()
            )));
        }
        logs.push(text);
    }
    match ghosts_kept_across_a_restart(&logs[0], &logs[1]) {
        Ok(raced) => {
            say!(
                "OK: {} ghosts kept in the flash image, read back after the restart and raced to their own state hashes",
                raced.len()
            );
            Ok(0)
        }
        Err(problems) => {
            for p in &problems {
                eprintln!("{p}");
            }
            Err(Failure::new(
                "FAILED (logs: target/check-ghosts-1.log, target/check-ghosts-2.log)",
            ))
        }
    }
}

/// The level names of `text`'s lines `ghost NAME<after>`.
fn ghost_lines<'t>(text: &'t str, after: &str) -> Vec<(&'t str, &'t str)> {
    text.lines()
        .filter_map(|line| {
            let rest = &line[line.find("ghost ")? + "ghost ".len()..];
            let (name, tail) = rest.split_once(' ')?;
            let name = name.trim_end_matches(':');
            tail.contains(after).then_some((name, tail))
        })
        .collect()
}

/// The check of [`check_ghosts`] on the two runs' logs: the names raced to
/// their ends, or what is wrong.
pub fn ghosts_kept_across_a_restart(first: &str, second: &str) -> Result<Vec<String>, Vec<String>> {
    let mut problems = Vec::new();
    let kept: Vec<&str> = ghost_lines(first, "")
        .into_iter()
        .filter(|(_, tail)| tail.starts_with("kept: "))
        .map(|(name, _)| name)
        .collect();
    if kept.is_empty() {
        problems.push("the first run kept no ghost".to_string());
    }
    let (levels, _) = parse_levels(second);
    let mut raced = Vec::new();
    for name in &kept {
        let read_back = ghost_lines(second, "replays to its hash")
            .iter()
            .any(|(n, _)| n == name);
        if !read_back {
            problems.push(format!(
                "{name}: the second run did not read its ghost back"
            ));
            continue;
        }
        let end = ghost_lines(second, "raced to its end")
            .into_iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, tail)| tail.split("state_hash=").nth(1))
            .map(|h| h.split_whitespace().next().unwrap_or(""));
        let level = levels.iter().find(|l| l.name == *name);
        match (end, level) {
            (Some(hash), Some(level)) if hash == level.hash => raced.push(name.to_string()),
            (Some(hash), Some(level)) => problems.push(format!(
                "{name}: the ghost ended on {hash}, the level on {}",
                level.hash
            )),
            (None, _) => problems.push(format!("{name}: the ghost did not race to its end")),
            (_, None) => problems.push(format!("{name}: no demo line in the second run")),
        }
    }
    // A level the first run won without keeping its ghost says why.
    let (first_levels, _) = parse_levels(first);
    for level in &first_levels {
        if !kept.contains(&level.name.as_str())
            && !first.contains(&format!("ghost {}: the run is longer than", level.name))
        {
            problems.push(format!("{}: neither kept nor said why not", level.name));
        }
    }
    if problems.is_empty() {
        Ok(raced)
    } else {
        Err(problems)
    }
}

/// The headless demo, exactly as `cargo xtask qemu --demo` runs it, its output
/// (QEMU's and defmt-print's) into `log`; QEMU's status.
fn run_demo(log: &Path, args: &[&str]) -> Outcome {
    if let Some(dir) = log.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    }
    let file = File::create(log)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", log.display())))?;
    let limit = runner::timeout(600)?;
    let tools = setup::m4_qemu()?;
    let elf = firmware::build(&Artifact::firmware("marble-qemu", "qemu", M4))?;
    let demo: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    match runner::headless(&tools, &elf, &demo, Output::File(&file), limit) {
        Ok(status) => Ok(status),
        // A timeout is a failed demo like any other: report it with the log.
        Err(failure) if failure.status == 124 => Ok(124),
        Err(failure) => Err(failure),
    }
}

/// Builds the host simulator (`cargo sim`) the demo checks compare with.
pub fn build_sim() -> Result<PathBuf, Failure> {
    say!("building the host simulator (cargo sim)…");
    firmware::build(&Artifact {
        package: "marble-rolling",
        bin: "sim",
        target: None,
        features: Some("tools"),
        quiet: true,
    })
    .map_err(|e| {
        Failure::new(format!(
            "cannot build the host simulator (bin sim, feature tools): {}",
            e.message
        ))
    })
}

/// Prints a table of each level as the board (`board`: its column name)
/// played it beside the simulator with the same stepper, and returns the levels
/// that do not agree, with the verdict.
pub fn compare_levels(
    sim: &PathBuf,
    levels: &[Level],
    stepping: &str,
    board: &str,
) -> Vec<(String, Verdict)> {
    let (steps, hash) = (format!("{board}.steps"), format!("{board} hash"));
    println!(
        "{}",
        row(["level", board, "sim", &steps, "s.steps", &hash, "sim hash", "result"])
    );
    let mut failed = Vec::new();
    for level in levels {
        let sim = simulate(sim, &level.name, stepping);
        let verdict = verdict(level, sim.as_ref());
        let sim = sim.unwrap_or_default();
        let or_dash = |field: &Option<String>| match field.as_deref() {
            Some(text) if !text.is_empty() => text.to_string(),
            _ => "-".to_string(),
        };
        println!(
            "{}",
            row([
                &level.name,
                &level.outcome,
                &or_dash(&sim.outcome),
                &level.steps,
                &or_dash(&sim.steps),
                &level.hash,
                &or_dash(&sim.hash),
                verdict.text(),
            ])
        );
        if verdict != Verdict::Ok {
            failed.push((level.name.clone(), verdict));
        }
    }
    failed
}

/// The simulator's arguments that choose `level`: `--level NAME` for a
/// built-in level, and for a generated maze, named after its arguments
/// (`maze-SEED-NxNxS-dD`, as `game::generate` names it), the arguments
/// themselves: `--generate SEED --size N --storeys S --difficulty D`.
pub fn level_args(level: &str) -> Vec<String> {
    match maze_args(level) {
        Some([seed, size, storeys, difficulty]) => vec![
            "--generate".into(),
            seed.into(),
            "--size".into(),
            size.into(),
            "--storeys".into(),
            storeys.into(),
            "--difficulty".into(),
            difficulty.into(),
        ],
        None => vec!["--level".into(), level.into()],
    }
}

/// `maze-SEED-NxNxS-dD` → `[SEED, N, S, D]` (each all digits, the two sizes
/// equal); anything else is a level's name.
fn maze_args(name: &str) -> Option<[&str; 4]> {
    let rest = name.strip_prefix("maze-")?;
    let (seed, rest) = rest.split_once('-')?;
    let (shape, difficulty) = rest.split_once("-d")?;
    let mut sides = shape.split('x');
    let (Some(x), Some(z), Some(storeys), None) =
        (sides.next(), sides.next(), sides.next(), sides.next())
    else {
        return None;
    };
    let number = |text: &str| !text.is_empty() && text.bytes().all(|b| b.is_ascii_digit());
    ([seed, x, storeys, difficulty].into_iter().all(number) && x == z)
        .then_some([seed, x, storeys, difficulty])
}

/// The simulator's result for `level` with the firmware's stepper, or `None`
/// when it printed no JSON.
pub fn simulate(sim: &PathBuf, level: &str, stepping: &str) -> Option<Sim> {
    let out = Command::new(sim)
        .args(level_args(level))
        .args(["--autopilot", "--json", "--stepping", stepping])
        .current_dir(workspace::root())
        .stdin(Stdio::null())
        .stderr(Stdio::null())
        .output()
        .ok()?;
    parse_sim(&String::from_utf8_lossy(&out.stdout))
}

#[cfg(test)]
mod ghost_tests {
    use super::ghosts_kept_across_a_restart;

    const FIRST: &str = "\
1.0 INFO  ghost corner kept: 473 bytes (0 older ghosts gave way)
1.1 INFO  demo 1/2 level=corner outcome=won steps=241 state_hash=88cb3b0d88d46483
1.2 WARN  ghost maze-12-4x4x2-d1: the run is longer than the 2044-byte buffer: not kept
1.3 INFO  demo 2/2 level=maze-12-4x4x2-d1 outcome=won steps=1021 state_hash=e2c162165bec26e4
";
    const SECOND: &str = "\
2.0 INFO  ghost corner: 473 bytes, replays to its hash: racing it (241 frames on the clock)
2.1 INFO  demo 1/2 level=corner outcome=won steps=241 state_hash=88cb3b0d88d46483
2.2 INFO  ghost corner raced to its end: 241 frames, state_hash=88cb3b0d88d46483 (its own)
2.3 INFO  demo 2/2 level=maze-12-4x4x2-d1 outcome=won steps=1021 state_hash=e2c162165bec26e4
";

    #[test]
    fn a_ghost_kept_and_raced_to_the_levels_hash_passes() {
        assert_eq!(
            ghosts_kept_across_a_restart(FIRST, SECOND),
            Ok(vec!["corner".to_string()])
        );
    }

    #[test]
    fn a_ghost_not_read_back_or_on_another_hash_fails() {
        let lost = SECOND.replace(
            "2.0 INFO  ghost corner: 473 bytes, replays",
            "2.0 INFO  ghost corner not raced",
        );
        assert!(ghosts_kept_across_a_restart(FIRST, &lost).is_err());
        let other = SECOND.replace(
            "state_hash=88cb3b0d88d46483 (its own)",
            "state_hash=0000000000000000 (its own)",
        );
        let problems = ghosts_kept_across_a_restart(FIRST, &other).unwrap_err();
        assert!(
            problems[0].contains("ended on 0000000000000000"),
            "{problems:?}"
        );
        // A level neither kept nor said why.
        let silent = FIRST.replace("1.2 WARN  ghost maze-12-4x4x2-d1: the run is longer than the 2044-byte buffer: not kept\n", "");
        assert!(ghosts_kept_across_a_restart(&silent, SECOND).is_err());
        assert!(ghosts_kept_across_a_restart("", "").is_err());
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
38.8 INFO  profile long-fall: 384 frames, instructions per frame: physics 900 (max 30123), autopilot 0, render 0
INFO  demo summary: 13/13 levels won
";
        assert_eq!(
            parse_worst_frames(log),
            [
                ("first-roll".to_string(), 1934),
                ("long-fall".to_string(), 30123)
            ]
        );
        let levels = ["first-roll".to_string()];
        let mut problems = Problems::default();
        check_worst_frames(log, &levels, 1_900, "M4", &mut problems);
        assert!(problems.0, "a level's 1 934 is over 1 900");
        let mut problems = Problems::default();
        check_worst_frames(log, &levels, 30_000, "M4", &mut problems);
        assert!(
            !problems.0,
            "a stress scene over the bound is reported only"
        );
        let mut problems = Problems::default();
        check_worst_frames("no profile here", &levels, 64_000, "M4", &mut problems);
        assert!(problems.0, "a log without profiles is a problem");
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
        assert!(!problems.0, "cuts in a stress scene are reported only");
        let mut problems = Problems::default();
        check_budget_cuts(log, &["drop-onto-marble".to_string()], &mut problems);
        assert!(problems.0, "a cut on a level is a problem");
        let mut problems = Problems::default();
        check_budget_cuts("no budget here", &[], &mut problems);
        assert!(problems.0, "a log without budget lines is a problem");
    }

    const LOG: &str = "\
\x1b[32mINFO \x1b[0m demo 1/3 level=corner outcome=won steps=1234 state_hash=00ab12CD34ef5678
└─ app::demo @ src/app/demo.rs:201
INFO  demo 2/3 level=pit outcome=fell steps=99 state_hash=ffffffffffffffff
noise demo 3/3 level=last outcome=won steps=7 state_hash=0123456789abcdef
INFO  cpu load: 123 busy instructions in 456 us of firmware time = 789 instructions/s = 1.23 % of a 64 MHz Cortex-M4 (60 frames/s, 1000 refreshes/s)
";

    fn level(name: &str, outcome: &str, steps: &str, hash: &str) -> Level {
        Level {
            name: name.into(),
            outcome: outcome.into(),
            steps: steps.into(),
            hash: hash.into(),
        }
    }

    #[test]
    fn a_generated_maze_is_simulated_from_its_arguments() {
        assert_eq!(
            level_args("maze-11-4x4x2-d1"),
            [
                "--generate",
                "11",
                "--size",
                "4",
                "--storeys",
                "2",
                "--difficulty",
                "1"
            ]
        );
        assert_eq!(level_args("corner"), ["--level", "corner"]);
        // Not a generated maze's name: a level of that name (a file, say).
        for name in [
            "maze-11-4x5x2-d1",
            "maze-11-4x4-d1",
            "maze-x-4x4x2-d1",
            "maze-11-4x4x2-d",
            "maze-11-4x4x2x1-d1",
            "maze--4x4x2-d1",
        ] {
            assert_eq!(level_args(name), ["--level", name], "{name}");
        }
    }

    #[test]
    fn the_stepper_is_read_from_the_log() {
        let log = "INFO  demo stepping=events\nINFO  demo 1/1 level=a outcome=won steps=1 state_hash=01\n";
        assert_eq!(parse_stepping(log), Some("events"));
        assert_eq!(
            parse_stepping("x demo stepping=fixed └─ app"),
            Some("fixed")
        );
        assert_eq!(parse_stepping("demo stepping=sideways"), None);
        assert_eq!(parse_stepping(LOG), None);
        // Not a level line: the total and the levels are unaffected.
        assert_eq!(parse_levels(log).1, Some(1));
    }

    #[test]
    fn colours_are_stripped() {
        assert_eq!(
            strip_colours("\x1b[1;31mred\x1b[0m plain \x1b[2K"),
            "red plain \x1b[2K"
        );
        assert_eq!(strip_colours("no escapes"), "no escapes");
    }

    #[test]
    fn level_lines_are_parsed_in_order() {
        let (levels, total) = parse_levels(&strip_colours(LOG));
        assert_eq!(total, Some(3));
        assert_eq!(
            levels,
            [
                level("corner", "won", "1234", "00ab12CD34ef5678"),
                level("pit", "fell", "99", "ffffffffffffffff"),
                level("last", "won", "7", "0123456789abcdef"),
            ]
        );
    }

    #[test]
    fn malformed_level_lines_are_skipped() {
        let (levels, total) = parse_levels("demo 1/2 level=a outcome=won steps=x state_hash=00\n");
        assert!(levels.is_empty());
        assert_eq!(total, Some(2));
        let (levels, total) = parse_levels("demo /  level=a\n");
        assert!(levels.is_empty());
        assert_eq!(total, None);
    }

    #[test]
    fn the_rightmost_level_record_of_a_line_wins() {
        let line = "demo 1/2 level=a outcome=won steps=1 state_hash=01 demo 2/2 level=b outcome=won steps=2 state_hash=02";
        assert_eq!(parse_levels(line).0, [level("b", "won", "2", "02")]);
    }

    #[test]
    fn cpu_load_is_read_in_hundredths() {
        assert_eq!(parse_cpu_load(LOG), Some(123));
        assert_eq!(
            parse_cpu_load("cpu load: x = 12.05 % of a 64 MHz"),
            Some(1205)
        );
        assert_eq!(parse_cpu_load("cpu load: x = .50 % of a 64 MHz"), Some(50));
        assert_eq!(parse_cpu_load("cpu load: x = 1.5 % of a 64 MHz"), None);
        assert_eq!(parse_cpu_load("cpu load: no time elapsed"), None);
        assert_eq!(parse_cpu_load("load = 1.00 % of a 64 MHz"), None);
    }

    #[test]
    fn sim_json_fields() {
        let out = "warming up\n{\"level\":\"x\"}\n{\"level\":\"corner\",\"outcome\":\"won\",\"steps\":1234,\"final\":{\"steps\":1},\"state_hash\":\"00AB12cd34ef5678\"}\n";
        let sim = parse_sim(out).unwrap();
        assert_eq!(
            sim,
            Sim {
                outcome: Some("won".into()),
                steps: Some("1234".into()),
                hash: Some("00AB12cd34ef5678".into())
            }
        );
        assert_eq!(parse_sim("error: no such level\n"), None);
        assert_eq!(parse_sim("{not json\n"), None);
    }

    #[test]
    fn verdicts() {
        let won = level("corner", "won", "1234", "00ab12cd34ef5678");
        let sim = parse_sim(r#"{"outcome":"won","steps":1234,"state_hash":"00AB12CD34EF5678"}"#);
        assert_eq!(verdict(&won, sim.as_ref()), Verdict::Ok);
        assert_eq!(verdict(&won, None), Verdict::SimFailed);
        let fell = level("pit", "fell", "1234", "00ab12cd34ef5678");
        assert_eq!(verdict(&fell, sim.as_ref()), Verdict::NotWon);
        let other = parse_sim(r#"{"outcome":"won","steps":1235,"state_hash":"00ab12cd34ef5678"}"#);
        assert_eq!(verdict(&won, other.as_ref()), Verdict::Mismatch);
        let hashless = parse_sim(r#"{"outcome":"won","steps":1234}"#);
        assert_eq!(verdict(&won, hashless.as_ref()), Verdict::Mismatch);
    }

    #[test]
    fn table_and_hundredths() {
        assert_eq!(
            row(["corner", "won", "won", "1234", "1234", "00ab", "00ab", "ok"]),
            "corner           won      won          1234     1234 00ab             00ab             ok"
        );
        assert_eq!(centi(300), "3.00");
        assert_eq!(centi(7), "0.07");
    }
}
