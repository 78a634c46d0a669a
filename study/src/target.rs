//! The target measurements: the `bench` firmware in QEMU mps2-an386 (Cortex-M4F)
//! and `bench_m0` in QEMU microbit (Cortex-M0), built and run by the project's
//! tasks (`cargo xtask bench-m4`, `cargo xtask bench-m0`), their logs parsed.

use std::collections::HashMap;
use std::process::{Command, Stdio};
use std::time::Instant;

/// One `BENCH` line.
#[derive(Clone, Debug)]
pub struct Count {
    /// Steps run.
    pub steps: u32,
    /// Instructions of the run.
    pub instructions: u64,
    /// End-state hash.
    pub hash: u64,
}

impl Count {
    /// Instructions per step.
    pub fn per_step(&self) -> f64 {
        self.instructions as f64 / self.steps.max(1) as f64
    }
}

/// Key: `(scene, backend, variant, step_log2)`.
pub type Key = (String, String, String, u32);

/// What one target run produced.
#[derive(Clone, Debug, Default)]
pub struct TargetRun {
    /// Counts by key.
    pub counts: HashMap<Key, Count>,
    /// The calibration line, as printed.
    pub calibration: String,
    /// The count of an empty closure (the counter's own overhead after calibration).
    pub empty: Option<u64>,
    /// Why it failed, when it did (counts may still be partial).
    pub error: Option<String>,
    /// Wall-clock seconds (build and run).
    pub seconds: f64,
}

/// Which target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cpu {
    /// Cortex-M4F on mps2-an386.
    M4,
    /// Cortex-M0 on microbit (nRF51).
    M0,
}

impl Cpu {
    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            Cpu::M4 => "Cortex-M4F (QEMU mps2-an386)",
            Cpu::M0 => "Cortex-M0 (QEMU microbit, nRF51)",
        }
    }
}

fn parse(text: &str, run: &mut TargetRun) {
    for line in text.lines() {
        if let Some(rest) = line.find("BENCH ").map(|i| &line[i + 6..]) {
            let f: Vec<&str> = rest.split_whitespace().collect();
            if f.len() < 9 {
                continue;
            }
            let (Ok(k), Ok(steps), Ok(instructions), Ok(hash)) = (
                f[3].parse::<u32>(),
                f[4].parse::<u32>(),
                f[5].parse::<u64>(),
                f[6].parse::<u64>(),
            ) else {
                continue;
            };
            run.counts.insert(
                (f[0].into(), f[1].into(), f[2].into(), k),
                Count {
                    steps,
                    instructions,
                    hash,
                },
            );
        } else if let Some(i) = line.find("CALIBRATION ") {
            run.calibration = line[i + 12..].trim().to_string();
        } else if let Some(i) = line.find("EMPTY ") {
            run.empty = line[i + 6..].trim().parse().ok();
        }
    }
}

/// Builds and runs the benchmark for `cpu` (`rates`: bit k selects 2^k steps/s).
pub fn run(cpu: Cpu, rates: u32) -> TargetRun {
    let start = Instant::now();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.args([
        "xtask",
        match cpu {
            Cpu::M4 => "bench-m4",
            Cpu::M0 => "bench-m0",
        },
    ]);
    cmd.arg(format!("--rates={rates}"));
    cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
    cmd.stdin(Stdio::null())
        .stderr(Stdio::piped())
        .stdout(Stdio::piped());
    let mut run = TargetRun::default();
    match cmd.output() {
        Ok(out) => {
            // defmt (M4) arrives on stdout through defmt-print; QEMU writes the
            // M0's SYS_WRITE0 console to stderr: read both.
            let stdout = String::from_utf8_lossy(&out.stdout).into_owned()
                + &String::from_utf8_lossy(&out.stderr);
            parse(&stdout, &mut run);
            if !out.status.success() || !stdout.contains("DONE") {
                let stderr = String::from_utf8_lossy(&out.stderr);
                let tail: Vec<&str> = stderr
                    .lines()
                    .rev()
                    .take(6)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev()
                    .collect();
                let so: Vec<&str> = stdout
                    .lines()
                    .rev()
                    .take(3)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev()
                    .collect();
                run.error = Some(format!(
                    "{} exited with {}: {} | {}",
                    cpu.name(),
                    out.status,
                    tail.join(" / "),
                    so.join(" / ")
                ));
            }
        }
        Err(e) => run.error = Some(format!("could not run cargo for {}: {e}", cpu.name())),
    }
    run.seconds = start.elapsed().as_secs_f64();
    run
}
