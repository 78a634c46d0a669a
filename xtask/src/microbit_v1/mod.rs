//! The micro:bit v1's check (`boards/microbit-v1`, nRF51822,
//! thumbv6m-none-eabi; the board's data is [`crate::boards::MICROBIT_V1`],
//! and `cargo microbit-v1` is the common runner, [`crate::game::play`]):
//!
//! * [`check()`] — `cargo xtask check-microbit-v1`: the QEMU demo against the
//!   host simulator (outcome, steps and `state_hash` per level), the LEDs
//!   rebuilt from QEMU's GPIO trace against the frames the firmware says it
//!   showed, the sensor path in the demo (`accel=mma8653fc` through QEMU's
//!   TWI stub, its re-init and fault counts), a `--demo --profile` run's
//!   per-level frame costs, then those of the difficulty-9 mazes and the
//!   stress scenes (`app::profile_scenes`, as the QEMU demo profiles them;
//!   printed, each line required; a level's or difficulty-9 maze's worst
//!   frame over 60 000 instructions, WORST_FRAME_M0, fails the check, and so
//!   does a stress scene's but four-shaken's, held to it as a goal), a two-second play without the demo (the stub found
//!   as the MMA8653FC, polled without a panic, the LEDs showing what the
//!   supervision decided), and the budgets (RAM: statics + stack
//!   high-water ≤ V1_RAM_BUDGET, 12 KiB; flash ≤ V1_FLASH_BUDGET, 144 KiB,
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
pub use qemu::run_image;

#[cfg(test)]
mod tests;
