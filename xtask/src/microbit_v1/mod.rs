//! The micro:bit v1 tasks (`boards/microbit-v1`, nRF51822, thumbv6m-none-eabi):
//!
//! * [`run`] — `cargo microbit-v1`: build, then `probe-rs run --chip
//!   nRF51822_xxAA` on a board (probe-rs is never installed for you:
//!   `cargo install probe-rs-tools --locked`); with `--demo` (or `--qemu`)
//!   the same ELF runs headless in `qemu-system-arm -M microbit` instead,
//!   its defmt log (semihosting) decoded by defmt-print.
//! * [`check()`] — `cargo xtask check-microbit-v1`: the QEMU demo against the
//!   host simulator (outcome, steps and `state_hash` per level), the LEDs
//!   rebuilt from QEMU's GPIO trace against the frames the firmware says it
//!   showed, the sensor path in the demo (`accel=mma8653fc` through QEMU's
//!   TWI stub, its re-init and fault counts), a `--demo --profile` run's
//!   per-level frame costs (printed; the 60 000-instruction worst frame is
//!   the physics' goal), a two-second play without the demo (the stub found
//!   as the MMA8653FC, polled without a panic, the LEDs showing what the
//!   supervision decided), and the budgets (RAM: statics + stack
//!   high-water ≤ V1_RAM_BUDGET, 12 KiB; flash ≤ V1_FLASH_BUDGET, 128 KiB,
//!   with the code bytes per module when over; CPU ≤
//!   V1_CPU_BUDGET_CENTIPERCENT, 20 % of 16 MHz).
//!
//! # The display, rebuilt from the GPIO trace
//!
//! QEMU runs with `-trace nrf51_gpio_update_output_irq -trace
//! nrf51_timer_set_count -D FILE`: one line per pin change (the firmware
//! writes the 12 matrix pins with one `OUT` write per BCM slice) and one
//! per TIMER capture. The firmware's display interrupt captures TIMER0 (its
//! 1 MHz clock) right before each `OUT` write, so the latest capture before
//! a pin change is that change's time in µs ([`Timeline`]; the 32-bit
//! counter is extended across wraps). The firmware logs each frame that
//! stayed on the LEDs for 80 ms or more as `display frame level=L t0=T0
//! t1=T1 rows=R0 R1 R2 R3 R4` (five hex digits per row, brightness 0..=15),
//! [`Timeline::perceived`] integrates the pin levels over `[T0, T1)`: each
//! LED's lit time (its row pin high and its column pin low, through the
//! DAL's table in `src/board/microbit_v1/leds.rs`, included here) over the
//! time its row was driven, × 15, rounded — what a viewer sees, as the
//! mps2 board's virtual matrix computes it. The check wants every logged
//! frame matched within one level per pixel (interrupt latency moves slice
//! edges by a microsecond or two), and per level at least one frame that
//! shows the maze and the marble (not blank, not the all-on win flash).

use std::path::PathBuf;
use std::process::Command;

use crate::error::{say, Failure, Outcome};
use crate::firmware::{self, Artifact};
use crate::process;
use crate::runner;
use crate::setup::{self, M0};

/// The firmware's own LED table (`leds::LED_MAP`, `decode_levels`), the very
/// file the firmware compiles: the check and the firmware cannot disagree
/// on the wiring (the table itself is tested against the DAL's in the core's
/// tests).
#[allow(dead_code)]
#[path = "../../../src/board/microbit_v1/leds.rs"]
mod leds;
mod check;
mod gpio_trace;
mod log;
mod qemu;

pub use check::check;
pub use gpio_trace::{hex_rows, max_difference, parse_frame, LoggedFrame, Timeline};
pub use qemu::{qemu_command, qemu_image_command, run_image};
use qemu::{qemu_run, qemu_run_with, Sink};

/// The firmware crate and binary.
pub const PACKAGE: &str = "marble-microbit-v1";
/// The firmware binary.
pub const BIN: &str = "microbit-v1";
/// probe-rs's name for the micro:bit v1's chip.
pub const CHIP: &str = "nRF51822_xxAA";

/// `cargo microbit-v1 [ARGS]`: on a board with probe-rs, or in QEMU with
/// `--demo` / `--qemu` (the rest of ARGS go to the firmware's semihosting
/// command line there, to probe-rs after the ELF otherwise).
pub fn run(args: &[String]) -> Outcome {
    let args = runner::drop_separators(args);
    let (image, args) = take_image(args)?;
    let qemu = args.iter().any(|arg| arg == "--demo" || arg == "--qemu");
    setup::target(M0)?;
    if qemu {
        let limit = runner::timeout(600)?;
        let tools = setup::m4_qemu()?;
        let elf = build()?;
        let firmware_args: Vec<String> = args.into_iter().filter(|arg| arg != "--qemu").collect();
        say!("running it headless in QEMU microbit (defmt log below)");
        let (status, _) = match &image {
            Some(image) => {
                say!(
                    "flash loaded from {} (the ELF only decodes the log)",
                    image.display()
                );
                let cmd = qemu_image_command(&tools.qemu, image, &firmware_args);
                qemu_run_with(cmd, &tools, &elf, None, Sink::Terminal, limit)?
            }
            None => qemu_run(&tools, &elf, &firmware_args, None, Sink::Terminal, limit)?,
        };
        return Ok(status);
    }
    if image.is_some() {
        return Err(Failure::new(
            "--image runs a flash image in QEMU: give --demo or --qemu with it (on a board, \
             drag the .hex onto MICROBIT instead)",
        )
        .status(2));
    }
    let elf = build()?;
    let probe = setup::probe_rs()?;
    say!("running it on the micro:bit v1 with probe-rs");
    let mut cmd = Command::new(probe);
    cmd.args(["run", "--chip", CHIP]).arg(&elf).args(&args);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        let error = cmd.exec();
        Err(Failure::new(format!("cannot run `{}`: {error}", process::shown(&cmd))).status(127))
    }
    #[cfg(not(unix))]
    Ok(process::code(process::status(&mut cmd)?))
}

/// Builds the firmware (`-p marble-microbit-v1 --target thumbv6m-none-eabi
/// --release`).
fn build() -> Result<PathBuf, Failure> {
    firmware::build(&Artifact::firmware(PACKAGE, BIN, M0))
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
mod tests;
