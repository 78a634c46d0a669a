//! The accuracy/cost study's entry point and its target benchmarks. The study
//! (`marble-study`'s `accuracy`) runs `cargo xtask bench-m4` and `bench-m0` and
//! parses their stdout: the `BENCH`, `CALIBRATION`, `EMPTY` and `DONE` lines.

use crate::boards::{Board, M0, M4, MICROBIT_V1, QEMU};
use crate::error::{say, Failure, Outcome};
use crate::process;
use crate::runner::{self, Output};
use crate::setup;
use crate::workspace;

/// `cargo xtask bench-m4 [ARGS...]`: the Cortex-M4F benchmark, headless in
/// QEMU mps2-an386, its defmt log decoded on stdout.
pub fn bench_m4(args: &[String]) -> Outcome {
    bench(&QEMU, "Cortex-M4F", args)
}

/// `cargo xtask bench-m0 [ARGS...]`: the Cortex-M0 benchmark in QEMU microbit,
/// its console on stdout.
pub fn bench_m0(args: &[String]) -> Outcome {
    bench(&MICROBIT_V1, "Cortex-M0", args)
}

/// `board`'s benchmark, headless on its QEMU machine, its output on stdout.
fn bench(board: &Board, core: &str, args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let machine = board.machine()?;
    let Some(bench) = &board.bench else {
        return Err(Failure::new(format!("the {} has no benchmark", board.name)).status(2));
    };
    let limit = runner::timeout(bench.timeout)?;
    let tools = bench.qemu_tools()?;
    let elf = bench.build()?;
    say!("running it in QEMU {} ({core})", machine.name);
    runner::headless(machine, bench, &tools, &elf, &args, Output::Terminal, limit)
}

/// `cargo xtask accuracy [ARGS...]`: the study, built with its own `study`
/// profile, which study/.cargo/config.toml defines, hence run from `study/`.
pub fn accuracy(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    // Everything its target runs need, installed up front rather than in the
    // middle of an hour-long run.
    setup::qemu_tools(true)?;
    setup::flip_link()?;
    setup::target(M4)?;
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
