//! `cargo xtask check-ghosts`: the QEMU board's ghosts kept across a restart.

use super::log::{parse_levels, read_log};
use super::run_demo;
use crate::error::{say, Failure, Outcome};
use crate::workspace;

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
        let status = run_demo(&crate::boards::QEMU, &log, &["--demo", "--ghosts"])?;
        let text = read_log(&log)?;
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
