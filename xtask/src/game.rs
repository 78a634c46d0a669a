//! The game on any board of [`crate::boards`], one runner for all: `cargo
//! qemu` (QEMU mps2-an386: in the terminal, or the headless demo), `cargo
//! microbit` (the v2, through probe-rs) and `cargo microbit-v1` (the v1
//! through probe-rs, or in QEMU's `microbit` machine with `--demo` or
//! `--qemu`). What differs is the board's data: a board with a QEMU machine
//! and no chip always runs in QEMU; one with a chip runs on it unless asked
//! for QEMU; one whose machine has a terminal plays there when stdin is one.

use std::io::IsTerminal;
use std::path::PathBuf;

use crate::boards::Board;
use crate::error::{say, Failure, Outcome};
use crate::runner::{self, Load, Output};
use crate::setup;
use crate::workspace;

/// `cargo xtask qemu|microbit|microbit-v1 [ARGS...]`: the rest of ARGS go to
/// the firmware's semihosting command line in QEMU, to probe-rs after the ELF
/// on a board. In QEMU: headless when `--demo` is given or stdin is not a
/// terminal (CI, pipes), else the game on the terminal; `--race` (a board
/// with a race firmware, QEMU mps2-an386): two boards racing, headless ([`crate::race`]); `--image
/// FILE` (a board QEMU also runs): that flash image instead of the ELF.
pub fn play(board: &Board, args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let has = |args: &[String], flag: &str| args.iter().any(|arg| arg == flag);
    let in_qemu = match (&board.qemu, board.chip) {
        (Some(_), None) => true,
        (Some(_), Some(_)) => has(&args, "--demo") || has(&args, "--qemu"),
        (None, _) => false,
    };
    if in_qemu && board.race.is_some() && has(&args, "--race") {
        return crate::race::run(board);
    }
    let (image, args) = if board.qemu.is_some() && board.chip.is_some() {
        take_image(args)?
    } else {
        (None, args)
    };
    if !in_qemu {
        if image.is_some() {
            return Err(Failure::new(
                "--image runs a flash image in QEMU: give --demo or --qemu with it (on a board, \
                 drag the .hex onto MICROBIT instead)",
            )
            .status(2));
        }
        return on_the_board(board, &args);
    }
    let machine = board.machine()?;
    // `--qemu` chooses QEMU over the board; the firmware has no such option.
    let args: Vec<String> = if board.chip.is_some() {
        args.into_iter().filter(|arg| arg != "--qemu").collect()
    } else {
        args
    };
    let limit = runner::timeout(board.game.timeout)?;
    let tools = board.game.qemu_tools()?;
    let elf = if has(&args, "--profile") {
        board.game.build_profiled()?
    } else {
        board.game.build()?
    };
    let headless = !machine.interactive || has(&args, "--demo") || !std::io::stdin().is_terminal();
    if !headless {
        // Relative to where the user is, since it is the user's path.
        let log = match std::env::var_os("QEMU_DEFMT_LOG") {
            Some(path) if !path.is_empty() => PathBuf::from(path),
            _ => workspace::target_dir()?.join("qemu-defmt.log"),
        };
        say!(
            "playing in QEMU {} (q quits; defmt log in {})",
            machine.name,
            log.display()
        );
        return runner::interactive(machine, &tools, &elf, &args, &log);
    }
    say!(
        "running it headless in QEMU {} (defmt log below)",
        machine.name
    );
    match &image {
        Some(image) => {
            say!(
                "flash loaded from {} (the ELF only decodes the log)",
                image.display()
            );
            let load = Load::Image {
                image,
                program: board.game.bin,
            };
            let cmd = runner::headless_command(machine, &tools.qemu, &load, &args);
            let (status, _) = runner::decoded(cmd, &tools, &elf, Output::Terminal, limit)?;
            Ok(status)
        }
        None => runner::headless(
            machine,
            &board.game,
            &tools,
            &elf,
            &args,
            Output::Terminal,
            limit,
        ),
    }
}

/// Builds the game and runs it on the board with `probe-rs run` (its defmt
/// log over RTT).
fn on_the_board(board: &Board, args: &[String]) -> Outcome {
    let Some(chip) = board.chip else {
        return Err(
            Failure::new(format!("the {} is not a chip probe-rs knows", board.name)).status(2),
        );
    };
    let elf = board.game.build()?;
    let probe = setup::probe_rs()?;
    say!("running it on the {} with probe-rs", board.name);
    runner::probe_rs(chip, &probe, &elf, args)
}

/// `--image PATH` (or `--image=PATH`) taken out of the arguments.
pub fn take_image(args: Vec<String>) -> Result<(Option<PathBuf>, Vec<String>), Failure> {
    let mut image = None;
    let mut rest = Vec::with_capacity(args.len());
    let mut args = args.into_iter();
    while let Some(arg) = args.next() {
        let path = match arg.strip_prefix("--image") {
            Some("") => args
                .next()
                .ok_or_else(|| Failure::new("--image needs a file (a .hex or an ELF)").status(2))?,
            Some(value) if value.starts_with('=') => value[1..].to_string(),
            _ => {
                rest.push(arg);
                continue;
            }
        };
        if image.replace(PathBuf::from(path)).is_some() {
            return Err(Failure::new("--image given twice").status(2));
        }
    }
    Ok((image, rest))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boards;

    #[test]
    fn the_image_option() {
        let strings = |list: &[&str]| list.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (image, rest) =
            take_image(strings(&["--demo", "--image", "x.hex", "--profile"])).unwrap();
        assert_eq!(image, Some(PathBuf::from("x.hex")));
        assert_eq!(rest, ["--demo", "--profile"]);
        let (image, rest) = take_image(strings(&["--image=y.hex", "--demo"])).unwrap();
        assert_eq!(image, Some(PathBuf::from("y.hex")));
        assert_eq!(rest, ["--demo"]);
        let (image, rest) = take_image(strings(&["--demo", "--images"])).unwrap();
        assert_eq!((image, rest), (None, strings(&["--demo", "--images"])));
        assert_eq!(
            take_image(strings(&["--demo", "--image"]))
                .unwrap_err()
                .status,
            2
        );
        assert!(take_image(strings(&["--image=a", "--image=b"])).is_err());
    }

    #[test]
    fn an_image_needs_qemu() {
        let args = ["--image".to_string(), "x.hex".to_string()];
        let failure = play(&boards::MICROBIT_V1, &args).unwrap_err();
        assert_eq!(failure.status, 2);
        assert!(
            failure.message.contains("give --demo or --qemu"),
            "{}",
            failure.message
        );
    }
}
