//! The accuracy/cost study's entry point and its target benchmarks. The study
//! (`marble-study`'s `accuracy`) runs `cargo xtask bench-m4` and `bench-m0` and
//! parses their stdout: the `BENCH`, `CALIBRATION`, `EMPTY` and `DONE` lines.

use crate::error::{say, Failure, Outcome};
use crate::firmware::{self, Artifact};
use crate::process;
use crate::runner::{self, Output};
use crate::setup::{self, M0, M4};
use crate::workspace;

/// `cargo xtask bench-m4 [ARGS...]`: the Cortex-M4F benchmark, headless in
/// QEMU mps2-an386, its defmt log decoded on stdout.
pub fn bench_m4(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let limit = runner::timeout(600)?;
    let tools = setup::m4_qemu()?;
    let elf = firmware::build(&Artifact::firmware("marble-qemu", "bench", M4))?;
    say!("running it in QEMU mps2-an386 (Cortex-M4F)");
    runner::headless(&tools, &elf, &args, Output::Terminal, limit)
}

/// `cargo xtask bench-m0 [ARGS...]`: the Cortex-M0 benchmark in QEMU microbit,
/// its console on stdout.
pub fn bench_m0(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let limit = runner::timeout(900)?;
    let qemu = setup::m0_qemu()?;
    let elf = firmware::build(&Artifact::firmware("marble-bench-m0", "bench_m0", M0))?;
    say!("running it in QEMU microbit (Cortex-M0)");
    runner::m0(&qemu, &elf, &args, limit)
}

/// `cargo xtask accuracy [ARGS...]`: the study, built with its own `study`
/// profile, which study/.cargo/config.toml defines, hence run from `study/`.
pub fn accuracy(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    // Everything its target runs need, installed up front rather than in the
    // middle of an hour-long run.
    setup::m4_qemu()?;
    setup::target(M0)?;
    let dir = workspace::root().join("study");
    if !dir.is_dir() {
        return Err(Failure::new(format!("{} not found", dir.display())).status(2));
    }
    let mut cmd = workspace::cargo();
    cmd.current_dir(&dir)
        .args([
            "run",
            "--profile",
            "study",
            "-p",
            "marble-study",
            "--bin",
            "accuracy",
            "--",
        ])
        .args(&args);
    say!("running the study: {}", process::shown(&cmd));
    Ok(process::code(process::status(&mut cmd)?))
}
