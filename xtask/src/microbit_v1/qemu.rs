//! Running the v1's firmware (an ELF or a flash image) in QEMU's `microbit`
//! machine, headless, its defmt log decoded by defmt-print.

use std::fs::File;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use super::BIN;
use crate::error::Failure;
use crate::runner;
use crate::setup;

/// Where a QEMU run's decoded log goes (the runner's [`runner::Output`]).
pub type Sink<'a> = runner::Output<'a>;

/// The QEMU command line (without the trace options).
pub fn qemu_command(qemu: &Path, elf: &Path, args: &[String]) -> Command {
    let program = elf
        .file_name()
        .map(|name| name.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut cmd = qemu_machine(qemu, &program, args);
    cmd.arg("-kernel").arg(elf);
    cmd
}

/// The QEMU command line for a flash image (`.hex`, as a person drags onto
/// the board, or ELF) put in place by QEMU's generic loader instead of
/// `-kernel`: the Cortex-M0 then boots from the vector table it wrote, as
/// the nRF51 does from flash. The firmware sees BIN as its program name.
pub fn qemu_image_command(qemu: &Path, image: &Path, args: &[String]) -> Command {
    let mut cmd = qemu_machine(qemu, BIN, args);
    let mut loader = std::ffi::OsString::from("loader,file=");
    // QEMU's option syntax: a comma inside a value is doubled.
    loader.push(image.to_string_lossy().replace(',', ",,"));
    cmd.arg("-device").arg(loader);
    cmd
}

/// QEMU's microbit machine, headless, its semihosting command line `program`
/// + `args`; no firmware yet.
fn qemu_machine(qemu: &Path, program: &str, args: &[String]) -> Command {
    let mut cmd = Command::new(qemu);
    cmd.args([
        "-M",
        "microbit",
        "-display",
        "none",
        "-monitor",
        "none",
        "-nodefaults",
    ])
    .args(runner::ICOUNT)
    .arg("-semihosting-config")
    .arg(runner::semihosting_config(program, args));
    cmd
}

/// Runs the ELF in QEMU microbit, headless, `trace` (if any) receiving the
/// GPIO and TIMER-capture trace; the defmt log (QEMU's stdout) through
/// defmt-print to `sink`. QEMU's status (the firmware's), else defmt-print's.
pub fn qemu_run(
    tools: &setup::Qemu,
    elf: &Path,
    args: &[String],
    trace: Option<&Path>,
    sink: Sink,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    let qemu = qemu_command(&tools.qemu, elf, args);
    qemu_run_with(qemu, tools, elf, trace, sink, limit)
}

/// Runs the flash image `image` (see [`qemu_image_command`]) headless with
/// `args`, its defmt log decoded with `elf` (which must be the image's ELF)
/// into `log`: QEMU's status (the firmware's), else defmt-print's.
pub fn run_image(
    tools: &setup::Qemu,
    elf: &Path,
    image: &Path,
    args: &[String],
    log: &File,
    limit: Duration,
) -> Result<u8, Failure> {
    let qemu = qemu_image_command(&tools.qemu, image, args);
    let (status, _) = qemu_run_with(qemu, tools, elf, None, Sink::File(log), limit)?;
    Ok(status)
}

/// [`qemu_run`] for a QEMU command line already made.
pub fn qemu_run_with(
    mut qemu: Command,
    tools: &setup::Qemu,
    elf: &Path,
    trace: Option<&Path>,
    sink: Sink,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    if let Some(trace) = trace {
        qemu.args(["-trace", "nrf51_gpio_update_output_irq"])
            .args(["-trace", "nrf51_timer_set_count"])
            .arg("-D")
            .arg(trace);
    }
    runner::decoded(qemu, tools, elf, sink, limit)
}
