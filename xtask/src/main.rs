//! The project's tasks (the cargo-xtask convention): `cargo xtask <task>`, or
//! the aliases `cargo qemu`, `cargo microbit`, `cargo web` and `cargo accuracy` from
//! .cargo/config.toml. Plain Rust instead of shell scripts, so that they run
//! wherever cargo does, install what they need on first use, and fail with a
//! message naming what and where.

mod boards;
mod demo;
mod error;
mod firmware;
mod game;
mod hex;
mod hex_check;
mod hex_files;
mod microbit_v1;
mod process;
mod profile;
mod properties;
mod race;
mod race_relay;
mod runner;
mod setup;
mod size;
mod stack_bound;
mod study;
mod symbols;
mod trace;
mod tty;
mod web;
mod workspace;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// The marble maze's tasks: firmware runners, checks and reports.
#[derive(Parser, Debug)]
#[command(name = "xtask", bin_name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

/// Everything after the task name is the firmware's (or the tool's): `--`
/// separators are dropped, so `cargo qemu -- --demo` and `cargo qemu --demo`
/// are the same.
#[derive(Subcommand, Debug)]
enum Task {
    /// Install what the QEMU firmware and the study need (thumbv7em-none-eabihf
    /// and thumbv6m-none-eabi targets, qemu-system-arm, flip-link, defmt-print).
    Setup {
        /// Also report on probe-rs (the micro:bit's runner, never installed).
        #[arg(long)]
        all: bool,
    },
    /// Play in QEMU mps2-an386 on the terminal; headless demo with --demo or
    /// without a terminal on stdin (exit status: the firmware's).
    Qemu {
        /// The headless demo: the autopilot plays every level and three
        /// generated mazes.
        #[arg(long)]
        demo: bool,
        /// Firmware arguments (semihosting command line).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Build the micro:bit v2 firmware and run it on the board (probe-rs).
    Microbit {
        /// Passed to probe-rs after the ELF.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Build the micro:bit v1 firmware and run it on the board (probe-rs), or
    /// with --demo / --qemu in QEMU microbit.
    MicrobitV1 {
        /// Firmware or probe-rs arguments.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// The micro:bit v1 demo in QEMU against the simulator, its LEDs rebuilt
    /// from the GPIO trace, and its budgets (V1_FLASH_BUDGET, V1_RAM_BUDGET…).
    CheckMicrobitV1,
    /// The study's Cortex-M4F benchmark in QEMU mps2-an386 (defmt log on stdout).
    BenchM4 {
        /// Benchmark arguments, e.g. --rates=MASK --backends=MASK.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// The study's Cortex-M0 benchmark in QEMU microbit (console on stdout).
    BenchM0 {
        /// Benchmark arguments, e.g. --rates=MASK --backends=MASK.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Check that the QEMU demo plays exactly like the host simulator, within
    /// the CPU budget (CPU_BUDGET_CENTIPERCENT, default 300).
    CheckDemo,
    /// QEMU keeps a ghost across a restart of the demo: `--demo --ghosts`
    /// twice on a fresh flash image; the second run races every ghost the
    /// first kept to its own state hash.
    CheckGhosts,
    /// The micro:bit firmware's flash and RAM against their budgets (FLASH_BUDGET,
    /// RAM_BUDGET), as a markdown table, and the stepping it links (must be events).
    SizeReport {
        /// Measure the existing build.
        #[arg(long)]
        no_build: bool,
        /// Measure this ELF instead of the micro:bit firmware.
        elf: Option<PathBuf>,
    },
    /// The full property run (profile soak): CASES per property, 42 shots each (both steppers).
    Properties {
        #[arg(default_value_t = 24000)]
        cases: u64,
    },
    /// Where the QEMU firmware's instructions go, by function (top TOP).
    QemuProfile {
        #[arg(default_value_t = 40)]
        top: usize,
        /// Profile the micro:bit v1 firmware in QEMU microbit instead.
        #[arg(long, conflicts_with = "bench")]
        v1: bool,
        /// Profile the study's M4 benchmark instead: one scene (incline,
        /// bounce, maze, corner), backend i8f24, event stepping.
        #[arg(long, value_name = "SCENE", value_parser = clap::builder::PossibleValuesParser::new(profile::SCENES))]
        bench: Option<String>,
        /// Count only a window of the run in the second and by-source tables:
        /// calls FROM to TO (1-based) of FUNCTION, e.g. `step_events:1933-2230`
        /// (one call a physics step).
        #[arg(long, value_name = "FUNCTION:FROM-TO")]
        window: Option<String>,
        /// With --v1: trace its `--demo --profile` run (an image with the
        /// `profile` feature), which plays the difficulty-9 mazes and the
        /// stress scenes after the levels.
        #[arg(long, requires = "v1")]
        scenes: bool,
    },
    /// Build the game for the browser (wasm32-unknown-unknown) and serve the
    /// page on 127.0.0.1 (`cargo web`).
    Web {
        /// Port to serve on; 0 picks a free one.
        #[arg(long, default_value_t = web::DEFAULT_PORT)]
        port: u16,
        /// Only build: print the module's path and size.
        #[arg(long)]
        no_serve: bool,
    },
    /// The browser test: the page in headless Chromium (keys, autopilot hashes
    /// against `cargo sim`, the editor's errors, the frame cost, a screenshot).
    WebTest {
        /// Also write the screenshot here (docs/tools.md shows docs/web.png).
        #[arg(long, value_name = "FILE")]
        screenshot: Option<PathBuf>,
    },
    /// The micro:bit files to drag onto MICROBIT (target/hex/): the universal
    /// hex for V1 and V2 and one plain Intel HEX per board.
    Hex {
        /// Also prove them: the micro:bit Foundation's npm library splits the
        /// universal hex into the ELFs' images (llvm-objcopy's), and the V1's
        /// wins the demo in QEMU from that .hex.
        #[arg(long)]
        check: bool,
        /// Level files to write into the boards' levels region (up to 8, each
        /// checked as `cargo sim -- --check` does).
        #[arg(long = "level", value_name = "FILE", num_args = 1..)]
        levels: Vec<PathBuf>,
    },
    /// The accuracy/cost study (writes docs/accuracy.md and docs/accuracy.png).
    Accuracy {
        /// The study's arguments (`cargo accuracy -- --help`).
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

impl Task {
    fn name(&self) -> &'static str {
        match self {
            Task::Setup { .. } => "setup",
            Task::Qemu { .. } => "qemu",
            Task::Microbit { .. } => "microbit",
            Task::MicrobitV1 { .. } => "microbit-v1",
            Task::CheckMicrobitV1 => "check-microbit-v1",
            Task::BenchM4 { .. } => "bench-m4",
            Task::BenchM0 { .. } => "bench-m0",
            Task::CheckDemo => "check-demo",
            Task::CheckGhosts => "check-ghosts",
            Task::SizeReport { .. } => "size-report",
            Task::Properties { .. } => "properties",
            Task::QemuProfile { .. } => "qemu-profile",
            Task::Web { .. } => "web",
            Task::WebTest { .. } => "web-test",
            Task::Hex { .. } => "hex",
            Task::Accuracy { .. } => "accuracy",
        }
    }

    fn run(self) -> error::Outcome {
        match self {
            Task::Setup { all } => setup::run(all, boards::ALL.iter().map(|b| b.game.target)),
            Task::Qemu { demo, args } => game::play(&boards::QEMU, &with_demo(demo, args)),
            Task::Microbit { args } => game::play(&boards::MICROBIT, &args),
            Task::MicrobitV1 { args } => game::play(&boards::MICROBIT_V1, &args),
            Task::CheckMicrobitV1 => microbit_v1::check(),
            Task::BenchM4 { args } => study::bench_m4(&args),
            Task::BenchM0 { args } => study::bench_m0(&args),
            Task::CheckDemo => demo::run(),
            Task::CheckGhosts => demo::check_ghosts(),
            Task::SizeReport { no_build, elf } => size::run(&boards::MICROBIT, no_build, elf),
            Task::Properties { cases } => properties::run(cases),
            Task::QemuProfile {
                top,
                v1,
                bench,
                window,
                scenes,
            } => {
                let subject = match bench {
                    Some(scene) => profile::Subject::Bench(
                        &boards::QEMU,
                        profile::SCENES
                            .iter()
                            .position(|&s| s == scene)
                            .unwrap_or(0),
                    ),
                    None if v1 && scenes => profile::Subject::Scenes(&boards::MICROBIT_V1),
                    None if v1 => profile::Subject::Demo(&boards::MICROBIT_V1),
                    None => profile::Subject::Demo(&boards::QEMU),
                };
                profile::run(top, subject, window.as_deref())
            }
            Task::Web { port, no_serve } => web::run(port, no_serve),
            Task::WebTest { screenshot } => web::test(screenshot),
            Task::Hex { check, levels } => {
                let written = hex_files::run(&levels)?;
                if check {
                    hex_check::check(&written)?;
                }
                Ok(0)
            }
            Task::Accuracy { args } => study::accuracy(&args),
        }
    }
}

/// The firmware's arguments with `--demo` back in front when clap took it as
/// our flag (it can only have been first, before any firmware argument).
fn with_demo(demo: bool, mut args: Vec<String>) -> Vec<String> {
    if demo {
        args.insert(0, "--demo".into());
    }
    args
}

/// The arguments without a `--` right after a task whose options are its own
/// (`web`, `web-test`, `hex`): the aliases put one there (`cargo web -- --port
/// 0`), and so do people (`cargo xtask hex -- --check`).
fn own_options(mut args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let own = args
        .get(1)
        .is_some_and(|task| task == "web" || task == "web-test" || task == "hex");
    if own && args.get(2).is_some_and(|a| a == "--") {
        args.remove(2);
    }
    args
}

fn main() -> ExitCode {
    let cli = Cli::parse_from(own_options(std::env::args_os().collect()));
    let task = cli.task.name();
    error::set_task(task);
    match cli.task.run() {
        Ok(status) => ExitCode::from(status),
        Err(failure) => {
            eprintln!("xtask {task}: {}", failure.message);
            ExitCode::from(failure.status.max(1))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Task {
        Cli::try_parse_from([&["xtask"], args].concat())
            .expect("parses")
            .task
    }

    fn qemu_args(args: &[&str]) -> Vec<String> {
        match parse(args) {
            Task::Qemu { demo, args } => runner::drop_separators(&with_demo(demo, args)),
            other => panic!("not qemu: {other:?}"),
        }
    }

    #[test]
    fn qemu_accepts_both_spellings() {
        assert_eq!(qemu_args(&["qemu", "--", "--demo"]), ["--demo"]);
        assert_eq!(qemu_args(&["qemu", "--demo"]), ["--demo"]);
        assert_eq!(
            qemu_args(&["qemu", "--demo", "--level", "x"]),
            ["--demo", "--level", "x"]
        );
        assert_eq!(
            qemu_args(&["qemu", "--level", "x", "--demo"]),
            ["--level", "x", "--demo"]
        );
        assert_eq!(qemu_args(&["qemu", "--", "--level=a,b"]), ["--level=a,b"]);
        assert!(qemu_args(&["qemu"]).is_empty());
    }

    #[test]
    fn bench_arguments_pass_through() {
        match parse(&["bench-m4", "--rates=1024", "--backends=1"]) {
            Task::BenchM4 { args } => assert_eq!(args, ["--rates=1024", "--backends=1"]),
            other => panic!("not bench-m4: {other:?}"),
        }
        match parse(&["accuracy", "--", "--quick"]) {
            Task::Accuracy { args } => assert_eq!(runner::drop_separators(&args), ["--quick"]),
            other => panic!("not accuracy: {other:?}"),
        }
    }

    #[test]
    fn defaults_and_usage_errors() {
        assert!(matches!(
            parse(&["properties"]),
            Task::Properties { cases: 24000 }
        ));
        assert!(matches!(
            parse(&["qemu-profile", "20"]),
            Task::QemuProfile {
                top: 20,
                v1: false,
                bench: None,
                window: None,
                scenes: false
            }
        ));
        assert!(matches!(
            parse(&["qemu-profile", "--v1", "--scenes"]),
            Task::QemuProfile {
                v1: true,
                scenes: true,
                ..
            }
        ));
        assert!(Cli::try_parse_from(["xtask", "qemu-profile", "--scenes"]).is_err());
        assert!(matches!(
            parse(&["qemu-profile", "--bench", "maze"]),
            Task::QemuProfile { top: 40, v1: false, bench: Some(scene), window: None, scenes: false } if scene == "maze"
        ));
        assert!(Cli::try_parse_from(["xtask", "qemu-profile", "--bench", "mazes"]).is_err());
        assert!(matches!(
            parse(&["size-report", "--no-build"]),
            Task::SizeReport {
                no_build: true,
                elf: None
            }
        ));
        assert!(matches!(
            parse(&["web"]),
            Task::Web {
                port: web::DEFAULT_PORT,
                no_serve: false
            }
        ));
        assert!(matches!(
            parse(&["web", "--port", "0", "--no-serve"]),
            Task::Web {
                port: 0,
                no_serve: true
            }
        ));
        assert!(Cli::try_parse_from(["xtask", "web", "--port", "70000"]).is_err());
        let alias = own_options(
            ["xtask", "web", "--", "--port", "0"]
                .map(Into::into)
                .to_vec(),
        );
        assert!(matches!(
            Cli::try_parse_from(alias).expect("parses").task,
            Task::Web { port: 0, .. }
        ));
        assert!(matches!(parse(&["hex"]), Task::Hex { check: false, levels } if levels.is_empty()));
        let hex = own_options(
            [
                "xtask", "hex", "--", "--level", "a.level", "b.level", "--check",
            ]
            .map(Into::into)
            .to_vec(),
        );
        assert!(matches!(
            Cli::try_parse_from(hex).expect("parses").task,
            Task::Hex { check: true, levels } if levels == [PathBuf::from("a.level"), PathBuf::from("b.level")]
        ));
        assert!(Cli::try_parse_from(["xtask", "hex", "--level"]).is_err());
        assert!(Cli::try_parse_from(["xtask", "size-report", "--bogus"]).is_err());
        assert!(Cli::try_parse_from(["xtask", "properties", "many"]).is_err());
        assert!(Cli::try_parse_from(["xtask", "nonsense"]).is_err());
    }
}
