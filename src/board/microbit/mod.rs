//! BBC micro:bit v2 (nRF52833, LSM303AGR, 5×5 LEDs, buttons A/B): the safe half.
//!
//! Only constants and pure functions live here, so `cargo test` on the host
//! covers every decision the firmware makes about timing, bus recovery and the
//! watchdog; what is left in the firmware crate `boards/microbit` is moving
//! bits between these and the pins. That crate needs `unsafe` (interrupt
//! handlers), which this library forbids. All game logic comes from
//! `crate::app` (feature `app`), exactly as in the QEMU build.
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
//!
//! # The I²C bus: never wait forever, clear what hangs
//!
//! An I²C slave reset or disturbed in the middle of a read can hold SDA low
//! forever, and the TWIM's async wait has no timeout: the input task would
//! wait until the watchdog reset, and since the slave keeps its state across
//! that reset, the next boot could hang the same way. So every transfer gets
//! [`I2C_TIMEOUT_MS`], and after a timeout (or any failed transfer) the
//! firmware takes the pins as GPIOs and runs [`clear_bus`], the I²C
//! specification's bus clear (UM10204 §3.1.16: up to nine SCL clocks until
//! the slave releases SDA, then a STOP), before the next transfer.
//!
//! # The watchdog: every task proves it runs
//!
//! The watchdog task pets only when every task's heartbeat moved since the
//! last pet ([`WatchdogGate`], the rule of `board::watchdog`, which the v1
//! shares), within [`WATCHDOG_TIMEOUT_TICKS`].
//!
//! # Shared with other boards
//!
//! The accelerometer link (axis map, polling, supervision, bus deadline:
//! `board::accel_link`, which the QEMU board models), the bus clear
//! (`board::i2c`) and the watchdog's rule (`board::watchdog`) are re-exported
//! here, so that this module lists everything the v2 runs with; the maze reach
//! and the ghosts' sizes are `board::game_sizes`', which QEMU runs too.

pub mod sleep;
pub mod speaker;
#[cfg(feature = "shared-flash")]
pub mod storage;

pub use super::accel_link::{
    AXIS_MAP, I2C_KHZ, I2C_TIMEOUT_MS, INPUT_PERIOD_MS, LONGEST_TRANSFER_BITS, SUPERVISOR,
    TWIM_COPY_BUFFER_BYTES,
};
use super::game_sizes;
pub use super::i2c::{
    clear_bus, BusClear, BusLines, BUS_CLEAR_HALF_PERIOD_US, BUS_CLEAR_MAX_CLOCKS,
    BUS_CLEAR_STRETCH_LIMIT,
};
pub use super::watchdog::{
    Heartbeats, Snapshot, Task, Tasks, Verdict, WatchdogGate, WATCHDOG_CHECK_MS,
};
use crate::input::buttons::ButtonConfig;
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

/// Accelerometer output data rate and settle time: the input path's
/// (see [`SUPERVISOR`] for the polling they are tuned with).
pub use crate::input::accel_timing::{ACCEL_ODR_HZ, ACCEL_SETTLE_MS};

/// How long the LSM303AGR needs after power-up before it answers, µs: the
/// figure CODAL gives ("the LSM needs at least 6.4ms from power-up",
/// codal-microbit-v2 `MicroBitCompass::autoDetect`, after
/// microbit-foundation/codal-microbit issue 33), more than the datasheet's
/// 5 ms boot.
pub const LSM303AGR_READY_US: u64 = 6_400;

/// When the input task sends its first `WHO_AM_I`, ms after the firmware's
/// start (a power-on reset starts both together): CODAL's `target_wait(10)`
/// before its probe, with margin over [`LSM303AGR_READY_US`]; sooner, the
/// first probe is a fault the supervisor has to recover.
pub const ACCEL_BOOT_MS: u64 = 10;

const _: () = assert!(ACCEL_BOOT_MS * 1000 > LSM303AGR_READY_US);

/// Watchdog period in ticks of its 32 768 Hz clock: 1 s. The watchdog task
/// must pet within it, which it does only while every task in [`Task::ALL`]
/// checks in (see [`WatchdogGate`]), or the board resets.
pub const WATCHDOG_TIMEOUT_TICKS: u32 = RTC_HZ;

/// The best times' flash region (byte addresses, whole 4 KiB NVMC pages): the
/// last 16 KiB of the nRF52833's 512 KiB, left out of `FLASH` in
/// `boards/microbit/memory.x` (a host test reads it there). Four pages, so that
/// the erases rotate: see `marble_rolling::records` and the wear figure in docs/testing.md.
pub const RECORDS: core::ops::Range<u32> = 0x7_C000..0x8_0000;

/// The start of the nRF52833's RAM, where the stack ends (flip-link puts the
/// statics at the top of the 128 KiB and the stack under them).
pub const RAM_BASE: usize = 0x2000_0000;

/// What the free stack is painted with at boot, so that the deepest word
/// the stack ever overwrote can be found (the firmware logs it as it grows:
/// the v2's stack is measured only on a board).
pub const STACK_PAINT: u32 = 0x5ac4_5ac4;

/// The ghosts' flash region (`marble_rolling::records::Ghosts`): the
/// [`GHOSTS_BYTES`](game_sizes::GHOSTS_BYTES) (four 4 KiB pages) below the
/// levels region, left out of `FLASH` in `boards/microbit/memory.x`.
pub const GHOSTS: core::ops::Range<u32> = 0x7_7000..0x7_7000 + game_sizes::GHOSTS_BYTES as u32;

// The v2's three flash regions (the levels, the best times, the ghosts) keep
// apart, and the ghosts' are whole 4 KiB pages: checked when the crate builds.
const _: () = {
    let levels = super::levels_region::V2;
    assert!(levels.end <= RECORDS.start || levels.start >= RECORDS.end);
    assert!(levels.end <= GHOSTS.start || levels.start >= GHOSTS.end);
    assert!(GHOSTS.end <= RECORDS.start);
    assert!(GHOSTS.start.is_multiple_of(4096) && GHOSTS.end.is_multiple_of(4096));
};

/// The longest run the v2 records and keeps as a ghost, in bytes (shared with
/// the QEMU board: [`game_sizes`]).
pub const GHOST_BYTES: usize = game_sizes::GHOST_BYTES;

/// The largest generated maze the endless run plays on the v2 (shared with
/// the QEMU board: [`game_sizes`]); the 5 × 5 view follows the marble.
pub const MAZE_REACH: crate::game::endless::Reach = game_sizes::MAZE_REACH;

/// What GPREGRET (the nRF52's general purpose retention register, kept in
/// System OFF) holds while the toy sleeps: this tag in the high nibble, the
/// level in the low one, so that a wake-up resumes at the start of that level
/// and any other value (a power-on reset clears it to 0) starts at level 1.
pub(crate) const SLEEP_TAG: u8 = 0xA0;

/// GPREGRET's value for sleeping on level `level` (levels past 15, which the 8
/// built-in levels never reach, resume at level 1).
pub const fn sleep_marker(level: u8) -> u8 {
    if level < 16 {
        SLEEP_TAG | level
    } else {
        0
    }
}

/// The level to start at after a reset with GPREGRET `gpregret`.
pub const fn level_after_reset(gpregret: u8) -> u8 {
    if gpregret & 0xF0 == SLEEP_TAG {
        gpregret & 0x0F
    } else {
        0
    }
}

/// Button timing for [`INPUT_PERIOD_MS`] (30 ms debounce, 1 s A+B hold).
pub const BUTTONS: ButtonConfig = ButtonConfig::DEFAULT_10MS;
