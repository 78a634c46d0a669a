//! Running the v1's firmware (an ELF or a flash image) headless in QEMU's
//! `microbit` machine ([`MICROBIT_V1`]'s), optionally with the GPIO and
//! TIMER-capture trace the display check reads.

use std::fs::File;
use std::path::Path;
use std::time::Duration;

use crate::boards::MICROBIT_V1;
use crate::error::Failure;
use crate::runner::{self, Load};
use crate::setup;

/// Where a QEMU run's decoded log goes (the runner's [`runner::Output`]).
pub type Sink<'a> = runner::Output<'a>;

/// Runs the ELF in QEMU microbit, headless, `trace` (if any) receiving the
/// GPIO and TIMER-capture trace; the defmt log (QEMU's stdout) through
/// defmt-print to `sink`. QEMU's status (the firmware's), else defmt-print's,
/// and the host time QEMU ran.
pub fn qemu_run(
    tools: &setup::Qemu,
    elf: &Path,
    args: &[String],
    trace: Option<&Path>,
    sink: Sink,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    let machine = MICROBIT_V1.machine()?;
    let mut qemu = runner::headless_command(machine, &tools.qemu, &Load::Elf(elf), args);
    if let Some(trace) = trace {
        qemu.args(["-trace", "nrf51_gpio_update_output_irq"])
            .args(["-trace", "nrf51_timer_set_count"])
            .arg("-D")
            .arg(trace);
    }
    runner::decoded(qemu, tools, elf, sink, limit)
}

/// Runs the flash image `image` (a .hex or an ELF, by QEMU's generic
/// loader) headless with `args`, its defmt log decoded with `elf` (which
/// must be the image's ELF) into `log`: QEMU's status (the firmware's), else
/// defmt-print's.
pub fn run_image(
    tools: &setup::Qemu,
    elf: &Path,
    image: &Path,
    args: &[String],
    log: &File,
    limit: Duration,
) -> Result<u8, Failure> {
    let machine = MICROBIT_V1.machine()?;
    let load = Load::Image {
        image,
        program: MICROBIT_V1.game.bin,
    };
    let qemu = runner::headless_command(machine, &tools.qemu, &load, args);
    let (status, _) = runner::decoded(qemu, tools, elf, Sink::File(log), limit)?;
    Ok(status)
}
