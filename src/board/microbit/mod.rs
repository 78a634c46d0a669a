//! BBC micro:bit v2 (nRF52833, LSM303AGR, 5×5 LEDs, buttons A/B): the safe half.
//!
//! Only constants and pure functions live here, so `cargo test` on the host
//! covers them. The wiring (embassy-nrf peripherals, the LSM303AGR driver, the
//! executors, interrupt bindings, the watchdog) is the firmware crate
//! `boards/microbit`; it needs `unsafe` (interrupt handlers), which this
//! library forbids.
//! All game logic comes from [`crate::app`], exactly as in the QEMU build.
//!
//! # Wiring (micro:bit v2 schematic)
//!
//! | what | pins |
//! | --- | --- |
//! | LED rows 1–5 (active high) | P0.21, P0.22, P0.15, P0.24, P0.19 |
//! | LED columns 1–5 (active low) | P0.28, P0.11, P0.31, P1.05, P0.30 |
//! | button A / B (active low, external pull-ups) | P0.14 / P0.23 |
//! | internal I²C (TWIM0): SDA / SCL | P0.16 / P0.08 |
//! | LSM303AGR accelerometer | I²C address 0x19 |
//!
//! # LED refresh: embassy-time, not a TIMER interrupt
//!
//! The display task waits for each BCM slice with `Timer::at` on absolute
//! deadlines, so it never drifts and never busy-waits. embassy-nrf's RTC1
//! time driver ticks at [`RTC_HZ`] = 32 768 Hz. A 5-row, 16-level BCM refresh
//! is 5 × 15 = 75 base ticks; at the wanted 100 Hz that is a 7 500 Hz base
//! tick, i.e. 4.37 RTC ticks. [`rtc_ticks_per_base_tick`] rounds *down* to 4
//! RTC ticks (122 µs, the shortest slice), giving a row time of 1.83 ms and a
//! refresh of [`refresh_millihz`] = 109.2 Hz (≥ 100 Hz). One RTC tick of
//! wake-up jitter (30.5 µs) only shortens or lengthens a slice, so the worst
//! error is a quarter of the least significant level. The display task runs
//! on a higher-priority interrupt executor so the game's computation in
//! thread mode cannot stretch a slice. A TIMER-interrupt scanner would be
//! exact to the microsecond but needs its own interrupt handler and shared
//! state; the RTC budget above makes it unnecessary.

use crate::input::buttons::ButtonConfig;
use crate::input::sensor::{Axis, AxisMap, AxisSource, SupervisorConfig};
use crate::matrix::base_tick_hz;

/// Frequency of the nRF RTC that drives embassy-time (`time-driver-rtc1`).
pub const RTC_HZ: u32 = 32_768;

/// LED matrix size.
pub const WIDTH: usize = 5;
/// LED matrix size.
pub const HEIGHT: usize = 5;

/// RTC ticks per BCM base tick for a wanted refresh rate: the largest whole
/// number of ticks that still reaches `refresh_hz` (at least 1).
pub const fn rtc_ticks_per_base_tick(refresh_hz: u32) -> u32 {
    let base = base_tick_hz::<HEIGHT>(refresh_hz);
    if base == 0 {
        return 1;
    }
    let ticks = RTC_HZ / base;
    if ticks == 0 {
        1
    } else {
        ticks
    }
}

/// Refresh rate actually obtained with `rtc_ticks` RTC ticks per base tick,
/// in millihertz.
pub const fn refresh_millihz(rtc_ticks: u32) -> u32 {
    let per_refresh = (rtc_ticks as u64) * (base_tick_hz::<HEIGHT>(1) as u64);
    if per_refresh == 0 {
        return 0;
    }
    ((RTC_HZ as u64) * 1000 / per_refresh) as u32
}

/// Sensor and button polling period. 100 Hz: twice the game's step rate.
pub const INPUT_PERIOD_MS: u64 = 10;

/// Accelerometer output data rate, Hz. Twice the polling rate, so every poll
/// finds a fresh sample and "no new data" really means a fault.
pub const ACCEL_ODR_HZ: u32 = 200;

/// Time to wait after (re)configuring the accelerometer before trusting its
/// output: high-resolution mode needs 7 samples at [`ACCEL_ODR_HZ`] (35 ms).
pub const ACCEL_SETTLE_MS: u64 = 40;

/// Watchdog period in ticks of its 32 768 Hz clock: 1 s. Every watchdog
/// channel (the input loop, the thread-executor liveness task) must check in
/// within it, or the board resets.
pub const WATCHDOG_TIMEOUT_TICKS: u32 = RTC_HZ;

/// How often the liveness task pets its watchdog channel, ms.
pub const WATCHDOG_PET_MS: u64 = 100;

/// Fault supervision tuned for [`INPUT_PERIOD_MS`].
pub const SUPERVISOR: SupervisorConfig = SupervisorConfig::DEFAULT;

/// Button timing for [`INPUT_PERIOD_MS`] (30 ms debounce, 1 s A+B hold).
pub const BUTTONS: ButtonConfig = ButtonConfig::DEFAULT_10MS;

/// LSM303AGR axes → board frame (`x` right, `y` up out of the LEDs, `z`
/// towards the player, who holds the board with the logo away and the edge
/// connector near; a flat board reads (0, +1000, 0)).
///
/// **Assumption (not verified on hardware here):** taken from the micro:bit
/// runtime (CODAL, `LSM303Accelerometer.cpp` + `CoordinateSpace(SIMPLE_CARTESIAN,
/// upside-down, 0°)`), which turns the raw registers into the documented
/// micro:bit frame as `(x, y, z)ₘ = (raw_x, −raw_y, raw_z)`, where the micro:bit
/// frame reads +1000 on x with the B (right) edge down, +1000 on y with the
/// edge connector down, −1000 on z lying screen-up. Hence, with the chip on the
/// back: raw `x` reads +1 g with the right edge down, raw `y` +1 g with the
/// logo edge down, raw `z` +1 g lying screen-down. Independent raw readings
/// (the "micro:bit v2 book" for Rust) agree for y and z. In the board frame:
/// `x = −raw_x`, `y = −raw_z`, `z = +raw_y`.
///
/// If the marble rolls the wrong way along one axis on a real board, flip
/// that row's sign here; the host tests in `tests/microbit_axes.rs` state
/// the expected readings per orientation and must be updated with it.
pub const AXIS_MAP: AxisMap = AxisMap {
    x: AxisSource::neg(Axis::X),
    y: AxisSource::neg(Axis::Z),
    z: AxisSource::pos(Axis::Y),
};
