//! The host simulator beside the firmware: building it, running it on a level
//! with the firmware's stepper, and the table of the two.

use std::path::PathBuf;
use std::process::{Command, Stdio};

use super::log::Level;
use crate::error::{say, Failure};
use crate::firmware::{self, Artifact};
use crate::workspace;

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
mod tests {
    use super::*;

    fn level(name: &str, outcome: &str) -> Level {
        Level {
            name: name.into(),
            outcome: outcome.into(),
            steps: "1234".into(),
            hash: "00ab12cd34ef5678".into(),
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
        let won = level("corner", "won");
        let sim = parse_sim(r#"{"outcome":"won","steps":1234,"state_hash":"00AB12CD34EF5678"}"#);
        assert_eq!(verdict(&won, sim.as_ref()), Verdict::Ok);
        assert_eq!(verdict(&won, None), Verdict::SimFailed);
        let fell = level("pit", "fell");
        assert_eq!(verdict(&fell, sim.as_ref()), Verdict::NotWon);
        let other = parse_sim(r#"{"outcome":"won","steps":1235,"state_hash":"00ab12cd34ef5678"}"#);
        assert_eq!(verdict(&won, other.as_ref()), Verdict::Mismatch);
        let hashless = parse_sim(r#"{"outcome":"won","steps":1234}"#);
        assert_eq!(verdict(&won, hashless.as_ref()), Verdict::Mismatch);
    }

    #[test]
    fn table_rows_are_padded() {
        assert_eq!(
            row(["corner", "won", "won", "1234", "1234", "00ab", "00ab", "ok"]),
            "corner           won      won          1234     1234 00ab             00ab             ok"
        );
    }
}
