//! The game firmware: `cargo qemu` (QEMU mps2-an386, in the terminal or as the
//! headless demo) and `cargo microbit` (a real board, through probe-rs).

use std::io::IsTerminal;
use std::path::PathBuf;

use crate::error::{say, Outcome};
use crate::firmware::{self, Artifact};
use crate::runner::{self, Output};
use crate::setup::{self, M4};
use crate::workspace;

/// `cargo xtask qemu [--demo] [ARGS...]`: headless when `--demo` is given or
/// stdin is not a terminal (CI, pipes), else the game on the terminal;
/// `--race`: two boards racing, headless ([`crate::race`]).
pub fn qemu(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    if args.iter().any(|arg| arg == "--race") {
        return crate::race::run();
    }
    let limit = runner::timeout(600)?;
    let tools = setup::m4_qemu()?;
    let elf = firmware::build(&Artifact::firmware("marble-qemu", "qemu", M4))?;
    if args.iter().any(|arg| arg == "--demo") || !std::io::stdin().is_terminal() {
        say!("running it headless in QEMU mps2-an386 (defmt log below)");
        runner::headless(&tools, &elf, &args, Output::Terminal, limit)
    } else {
        // Relative to where the user is, since it is the user's path.
        let log = match std::env::var_os("QEMU_DEFMT_LOG") {
            Some(path) if !path.is_empty() => PathBuf::from(path),
            _ => workspace::target_dir()?.join("qemu-defmt.log"),
        };
        say!(
            "playing in QEMU mps2-an386 (q quits; defmt log in {})",
            log.display()
        );
        runner::interactive(&tools, &elf, &args, &log)
    }
}

/// `cargo xtask microbit [ARGS...]`: build, then `probe-rs run` on the board
/// (defmt over RTT).
pub fn microbit(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    setup::target(M4)?;
    setup::flip_link()?;
    let elf = firmware::build(&Artifact::firmware("marble-microbit", "microbit", M4))?;
    let probe = setup::probe_rs()?;
    say!("running it on the micro:bit v2 with probe-rs");
    runner::probe_rs(&probe, &elf, &args)
}
