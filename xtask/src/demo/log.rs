//! Reading the firmware's demo log: the per-level lines, the stepper, the CPU
//! load and the per-frame profile and flight-budget lines; and the log files
//! every board's checks write and read back.

use std::fs::File;
use std::path::Path;

use crate::error::Failure;

/// A new log file at `path`, its directory made.
pub fn create_log(path: &Path) -> Result<File, Failure> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    }
    File::create(path).map_err(|e| Failure::new(format!("cannot write {}: {e}", path.display())))
}

/// The log at `path` as plain text ([`strip_colours`]), written back so, to
/// be kept for reading.
pub fn read_log(path: &Path) -> Result<String, Failure> {
    let bytes = std::fs::read(path)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", path.display())))?;
    let text = strip_colours(&String::from_utf8_lossy(&bytes));
    let _ = std::fs::write(path, &text);
    Ok(text)
}

/// One level as the firmware reported it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level {
    pub name: String,
    pub outcome: String,
    pub steps: String,
    pub hash: String,
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
/// `cpu load: … = X.YY % of a 64 MHz …` (any board's clock).
pub fn parse_cpu_load(log: &str) -> Option<u64> {
    log.lines().find_map(cpu_load_of)
}

fn cpu_load_of(line: &str) -> Option<u64> {
    let start = line.find("cpu load: ")? + "cpu load: ".len();
    let line = &line[start..];
    line.rmatch_indices(" % of a ").find_map(|(end, of)| {
        let clock = &line[end + of.len()..];
        let unit = clock.trim_start_matches(|c: char| c.is_ascii_digit());
        if unit.len() == clock.len() || !unit.starts_with(" MHz") {
            return None;
        }
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

/// Hundredths as `X.YY`.
pub fn centi(value: u64) -> String {
    format!("{}.{:02}", value / 100, value % 100)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(
            parse_cpu_load("cpu load: x = 18.58 % of a 16 MHz Cortex-M0"),
            Some(1858)
        );
        assert_eq!(parse_cpu_load("cpu load: x = 1.00 % of a fast MHz"), None);
        assert_eq!(parse_cpu_load("cpu load: x = 1.00 % of a 16 GHz"), None);
        assert_eq!(centi(300), "3.00");
        assert_eq!(centi(7), "0.07");
    }
}
