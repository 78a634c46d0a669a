//! BBC micro:bit v1 (nRF51822: Cortex-M0, 16 KiB RAM, 256 KiB flash): the
//! safe, host-tested half. The register-level half is the firmware crate
//! `boards/microbit-v1` (`marble-microbit-v1`).
//!
//! * [`leds`]: the 5×5 LEDs on their 3 × 9 row/column lines (the DAL's
//!   table, with its source), and the GPIO `OUT` words of a scan step.
//! * The logical-to-electrical scan conversion: the shared
//!   [`Scanner`] runs twice over — the app's display
//!   task scans the game's 5×5 frame ([`frame_from_refresh`] takes one
//!   refresh of those steps back to the frame), the frame is rewired onto the
//!   3 × 9 lines ([`electrical_frame`]) and scanned again as a 9-wide,
//!   3-row matrix into a [`Schedule`] of 12 `OUT` words with their
//!   durations, which the firmware's TIMER interrupt plays.
//! * [`Options`] (the semihosting command line), the CPU-load arithmetic
//!   for a 16 MHz Cortex-M0 ([`Calibration`], [`LoadReport`]), the
//!   accelerometers a v1 may carry ([`Accelerometer`], identified by
//!   `WHO_AM_I`), and the memory map ([`FLASH_BYTES`], [`RAM_BYTES`],
//!   [`FLASH_PAGE_BYTES`]).
//! * [`sensor`]: the accelerometer's poll loop (probe, configure, poll,
//!   faults, bus clear), generic over the bus: the firmware runs it on its
//!   TWI, the host tests on the virtual chips ([`virtual_nxp`]) on a
//!   virtual TWI ([`virtual_twi`]).
//!
//! # Memory map
//!
//! The micro:bit v1's nRF51822 (QFAA/QFAC variant on the board) has 256 KiB
//! of flash in 1 KiB pages and 16 KiB of RAM. embassy-nrf 0.11 describes the
//! `nrf51` feature with 4 KiB flash pages and 128 KiB of flash (the smallest
//! nRF51 variants), which is wrong for this board: whoever adds flash storage
//! later must erase 1 KiB pages and may use the whole 256 KiB.

pub mod accel;
pub mod leds;
pub mod nxp_driver;
pub mod sensor;
pub mod twi;
pub mod virtual_nxp;
pub mod virtual_twi;

pub use accel::{identify, Accelerometer, Probe, PROBES};

use crate::matrix::{base_tick_hz, Brightness, Frame, ScanStep, Scanner, BCM_BITS, MAX_BRIGHTNESS};
use leds::{out_word, COLS, LED_MAP, ROWS, SIZE};

/// The logical display: 5 × 5 pixels.
pub type Picture = Frame<SIZE, SIZE>;
/// The electrical matrix: `COLS` (9) column lines wide, `ROWS` (3) rows high.
pub(crate) type Electrical = Frame<COLS, ROWS>;

/// Display width, pixels.
pub const WIDTH: usize = SIZE;
/// Display height, pixels.
pub const HEIGHT: usize = SIZE;

/// Flash of the micro:bit v1's nRF51822, bytes.
pub const FLASH_BYTES: u32 = 256 * 1024;
/// RAM of the micro:bit v1's nRF51822, bytes.
pub const RAM_BYTES: u32 = 16 * 1024;
/// The nRF51822's flash page (erase unit), bytes (FICR `CODEPAGESIZE`).
pub const FLASH_PAGE_BYTES: u32 = 1024;
/// Start of RAM.
pub const RAM_BASE: usize = 0x2000_0000;
/// The word the firmware paints its free stack with at boot, to measure the
/// stack's high-water mark at the end of a run.
pub const STACK_PAINT: u32 = 0x5ac4_5ac4;

/// Budget: static RAM plus the stack's high-water mark, bytes (12 of 16 KiB).
pub const RAM_BUDGET_BYTES: u32 = 12 * 1024;
/// Budget: flash (text + data), bytes: half of the chip's 256 KiB (issue 27),
/// room for the event stepper.
pub const FLASH_BUDGET_BYTES: u32 = 128 * 1024;
/// The watchdog's period in ticks of its 32 768 Hz clock: 2 s, twice the
/// v2's. The v1's event-stepped drops take up to ~900 000 instructions a
/// frame (`cargo microbit-v1 -- --demo --profile`), and the game task runs
/// late frames back to back: in QEMU (about half a real M0's speed) every
/// task but the game stalled for half a second in grand-tour. A second of
/// margin over that; the pets follow the rule every board shares
/// (`board::watchdog::WatchdogGate`).
pub const WATCHDOG_TIMEOUT_TICKS: u32 = 2 * 32_768;

/// Budget: the demo's CPU load, hundredths of a percent of `CPU_HZ`.
pub const CPU_BUDGET_CENTIPERCENT: u64 = 2000;

/// The nRF51822's core clock (HFCLK), Hz.
pub(crate) const CPU_HZ: u64 = 16_000_000;
/// The firmware's TIMERs count at 16 MHz / 2^4 = 1 MHz: one tick a µs.
pub const TIMER_PRESCALER: u8 = 4;
/// Ticks per second of the TIMERs at [`TIMER_PRESCALER`].
pub(crate) const TIMER_HZ: u32 = 16_000_000 >> TIMER_PRESCALER;

/// Full refreshes of the LEDs per second (the app's `REFRESH_HZ`).
pub const REFRESH_HZ: u32 = 100;
/// One BCM base tick, µs: a refresh is `ROWS × 15` base ticks, so 100 Hz
/// wants 4 500 Hz = 222.2 µs; rounded down to whole µs (222 µs, a refresh
/// of 9.99 ms = 100.1 Hz).
pub const BASE_TICK_US: u32 = TIMER_HZ / base_tick_hz::<ROWS>(REFRESH_HZ);
/// One full refresh, µs.
pub const REFRESH_US: u32 = BASE_TICK_US * Scanner::<COLS, ROWS>::TICKS_PER_REFRESH;

/// Slices (scan steps) in one refresh of the electrical matrix: 3 rows × 4
/// BCM bits.
pub const SLICES: usize = ROWS * BCM_BITS;

/// The picture a refresh of `steps` of a 5×5 [`Scanner`] shows: each lit
/// pixel's on-time in base ticks is its brightness (a BCM refresh lights a
/// pixel of brightness `b` for exactly `b` ticks). Steps beyond one refresh
/// add up (and saturate at [`MAX_BRIGHTNESS`]).
pub fn frame_from_refresh<I: IntoIterator<Item = ScanStep>>(steps: I) -> Picture {
    let mut rows = [[0 as Brightness; SIZE]; SIZE];
    for step in steps {
        let Some(row) = rows.get_mut(step.row) else {
            continue;
        };
        let ticks = Brightness::try_from(step.ticks).unwrap_or(MAX_BRIGHTNESS);
        let mut lit = step.columns;
        while lit != 0 {
            let x = lit.trailing_zeros() as usize;
            lit &= lit - 1;
            if let Some(level) = row.get_mut(x) {
                *level = level.saturating_add(ticks).min(MAX_BRIGHTNESS);
            }
        }
    }
    Frame::from_rows(rows)
}

/// The picture rewired onto the electrical matrix: pixel `(x, y)` goes to
/// column `c`, row `r` of [`LED_MAP`]`[y][x] = (r, c)`. The two crossings
/// without an LED stay 0.
pub fn electrical_frame(picture: &Picture) -> Electrical {
    let mut out = Electrical::new();
    for (y, row) in LED_MAP.iter().enumerate() {
        for (x, &(r, c)) in row.iter().enumerate() {
            out.set(usize::from(c), usize::from(r), picture.get(x, y));
        }
    }
    out
}

/// The picture an electrical frame shows (the inverse of
/// [`electrical_frame`]; unused crossings are ignored).
pub fn picture_of(electrical: &Electrical) -> Picture {
    let mut out = Picture::new();
    for (y, row) in LED_MAP.iter().enumerate() {
        for (x, &(r, c)) in row.iter().enumerate() {
            out.set(x, y, electrical.get(usize::from(c), usize::from(r)));
        }
    }
    out
}

/// One slice of a refresh: the GPIO `OUT` word (matrix pins only) and how
/// long it stays, µs.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Slice {
    /// The `OUT` bits of P0.04 ..= P0.15 (see [`leds::out_word`]).
    pub out: u32,
    /// Duration, µs (a power of two times [`BASE_TICK_US`]).
    pub us: u32,
}

/// One refresh of the electrical matrix, in playing order.
pub type Schedule = [Slice; SLICES];

/// A schedule with every LED dark for a whole refresh.
pub const DARK_SCHEDULE: Schedule = {
    let mut schedule = [Slice {
        out: leds::DARK,
        us: 0,
    }; SLICES];
    let mut i = 0;
    while i < SLICES {
        // The same slice lengths as a real refresh (8, 4, 2, 1 base ticks per row).
        schedule[i].us = BASE_TICK_US << (BCM_BITS - 1 - i % BCM_BITS);
        i += 1;
    }
    schedule
};

/// The schedule that shows `picture`: rewired ([`electrical_frame`]),
/// scanned by the shared [`Scanner`] as a 9 × 3 matrix (rows top to bottom,
/// each row's BCM slices most significant first), each step turned into its
/// `OUT` word and duration.
pub fn schedule(picture: &Picture) -> Schedule {
    let mut scanner = Scanner::<COLS, ROWS>::with_frame(&electrical_frame(picture));
    let mut out = [Slice::default(); SLICES];
    for slice in out.iter_mut() {
        let step = scanner.next_step();
        *slice = Slice {
            out: out_word(step.row, step.columns),
            us: step.ticks.saturating_mul(BASE_TICK_US),
        };
    }
    out
}

/// The scan steps (row, lit columns, base ticks) a schedule drives, as the
/// electrical matrix's [`ScanStep`]s: what a GPIO observer integrates.
pub fn schedule_steps(schedule: &Schedule) -> impl Iterator<Item = ScanStep> + '_ {
    schedule.iter().map(|slice| {
        let (rows, lit) = leds::decode_levels(slice.out);
        ScanStep {
            row: if rows == 0 {
                ROWS
            } else {
                rows.trailing_zeros() as usize
            },
            columns: lit,
            ticks: slice.us / BASE_TICK_US.max(1),
        }
    })
}

/// A picture as five rows of five hex digits (row `y` is digits `x` = 0..5,
/// most significant first): how the firmware logs a frame and the xtask
/// reads it.
pub fn rows_hex(picture: &Picture) -> [u32; SIZE] {
    let mut out = [0u32; SIZE];
    for (word, row) in out.iter_mut().zip(picture.rows()) {
        *word = row
            .iter()
            .fold(0u32, |acc, &level| (acc << 4) | u32::from(level & 0xf));
    }
    out
}

// ---------------------------------------------------------------------------
// Command line
// ---------------------------------------------------------------------------

/// How the firmware was started: its semihosting command line under QEMU
/// (`cargo microbit-v1 -- --demo`); on a real board there is none (the
/// defaults: play).
///
/// * `--demo`: the autopilot plays every built-in level once and the first
///   three generated mazes of the endless run, then the firmware exits
///   through semihosting (0 only if every level was won).
/// * `--seconds=N`: play (no autopilot) for `N` seconds of firmware time,
///   then exit 0 — a headless run of the play mode, e.g. to see the sensor
///   supervision give up on QEMU's stub accelerometer.
/// * `--profile`: with `--demo`, a profile of each level's frames
///   (`app::profiled_demo`).
/// * `--no-frame-log`: do not log the displayed frames (by default headless
///   runs log every frame that stays on the LEDs for
///   [`FRAME_LOG_MIN_REFRESHES`] refreshes or more, for the xtask's GPIO
///   check).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Options {
    /// Run the headless demo.
    pub demo: bool,
    /// Stop playing after this many seconds (headless play).
    pub seconds: Option<u32>,
    /// Log the frames shown, with their times.
    pub frame_log: bool,
    /// With `--demo`: count each frame's instructions and log a profile
    /// per level (interrupts off while counting: the LEDs and the CPU load
    /// of such a run are not the demo's).
    pub profile: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            demo: false,
            seconds: None,
            frame_log: true,
            profile: false,
        }
    }
}

impl Options {
    /// Parses the command-line words (the program name included or not;
    /// unknown words and malformed numbers are ignored).
    pub fn parse<'a>(args: impl IntoIterator<Item = &'a str>) -> Options {
        let mut options = Options::default();
        for arg in args {
            match arg {
                "--demo" => options.demo = true,
                "--no-frame-log" => options.frame_log = false,
                "--profile" => options.profile = true,
                _ => {
                    if let Some(Ok(seconds)) = arg.strip_prefix("--seconds=").map(str::parse::<u32>)
                    {
                        options.seconds = Some(seconds);
                    }
                }
            }
        }
        options
    }

    /// Whether the run ends by itself (the demo, or a timed play).
    pub fn headless(&self) -> bool {
        self.demo || self.seconds.is_some()
    }
}

/// Frames shown for at least this many whole refreshes are logged (80 ms):
/// long enough that the GPIO check integrates whole BCM refreshes.
pub const FRAME_LOG_MIN_REFRESHES: u32 = 8;

// ---------------------------------------------------------------------------
// CPU load
// ---------------------------------------------------------------------------

/// The `-icount shift=N` of headless runs: each instruction is `2^N` ns of
/// virtual time, so a 1 MHz TIMER advances 1000 / 2^N ticks per instruction.
pub(crate) const ICOUNT_SHIFT: u32 = 7;

/// TIMER µs per instruction × 1000 that `-icount shift=7` gives (128).
pub(crate) const EXPECTED_MILLI_US_PER_INSTRUCTION: u64 = 1 << ICOUNT_SHIFT;

/// µs per instruction, measured by timing a block of known length (a NOP
/// loop) on the 1 MHz TIMER, as `study/bench-m0` does at 16 MHz.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// Instructions in the timed block.
    pub instructions: u32,
    /// µs the block took, the timing overhead removed.
    pub us: u32,
    /// µs of the timing itself (an empty block).
    pub overhead_us: u32,
}

impl Calibration {
    /// What `-icount shift=7` should measure.
    pub const NOMINAL: Calibration = Calibration {
        instructions: 1000,
        us: EXPECTED_MILLI_US_PER_INSTRUCTION as u32,
        overhead_us: 0,
    };

    /// µs per instruction × 1000 (128 expected).
    pub fn milli_us_per_instruction(&self) -> u64 {
        if self.instructions == 0 {
            return 0;
        }
        u64::from(self.us) * 1000 / u64::from(self.instructions)
    }

    /// Whether the measurement matches `-icount shift=7` within 1 %.
    pub fn matches_icount(&self) -> bool {
        let measured = self.milli_us_per_instruction();
        measured.abs_diff(EXPECTED_MILLI_US_PER_INSTRUCTION) * 100
            <= EXPECTED_MILLI_US_PER_INSTRUCTION
    }

    /// Instructions executed in `us` µs of busy time (rounded to nearest).
    pub fn instructions(&self, us: u64) -> u64 {
        if self.us == 0 {
            return 0;
        }
        // 64-bit arithmetic (no 128-bit division on the M0): exact for
        // `us` below 2^64 / instructions, over two centuries of busy time.
        let cal = u64::from(self.us);
        let scaled = us.saturating_mul(u64::from(self.instructions));
        scaled.saturating_add(cal / 2) / cal
    }
}

/// A reading of the CPU meter: µs since the clock started and µs spent in
/// the executor's WFI.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// µs since start.
    pub total_us: u64,
    /// µs asleep.
    pub idle_us: u64,
}

/// CPU load between two [`Sample`]s.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadReport {
    /// Firmware time covered, µs.
    pub firmware_us: u64,
    /// Busy instructions (outside WFI).
    pub busy_instructions: u64,
    /// Busy instructions per second of firmware time.
    pub instructions_per_second: u64,
    /// That as a share of a `CPU_HZ` core at one instruction per cycle, in
    /// hundredths of a percent. A Cortex-M0 takes more than one cycle for
    /// loads, stores and taken branches, so this is a lower bound of the
    /// real load.
    pub centipercent_of_16mhz: u64,
}

impl LoadReport {
    /// The load between `start` and `end`; `None` when no time passed or the
    /// samples are out of order.
    pub fn between(calibration: &Calibration, start: Sample, end: Sample) -> Option<LoadReport> {
        let total = end.total_us.checked_sub(start.total_us)?;
        let idle = end.idle_us.checked_sub(start.idle_us)?;
        if total == 0 {
            return None;
        }
        let busy_instructions = calibration.instructions(total.saturating_sub(idle));
        let instructions_per_second = busy_instructions.saturating_mul(1_000_000) / total;
        let centipercent_of_16mhz = instructions_per_second.saturating_mul(10_000) / CPU_HZ;
        Some(LoadReport {
            firmware_us: total,
            busy_instructions,
            instructions_per_second,
            centipercent_of_16mhz,
        })
    }
}

/// The largest generated maze the endless run plays on the v1
/// ([`crate::game::endless`]): 7 cells a side on up to four storeys, so that
/// its demo plays the same mazes as QEMU's. Its slot keeps 228 B of tiles and
/// 28 of name in the game task's static RAM, and its text (at most 1 104 B) is
/// on the stack only while it is parsed, between two levels, far above the
/// stack's deepest call (`cargo xtask check-microbit-v1` has the figures;
/// docs/boards.md). Larger mazes would fit the RAM too, but the v1's physics
/// is already over its frame goal on the larger built-in levels.
pub const MAZE_REACH: crate::game::endless::Reach = crate::game::endless::Reach {
    size: 7,
    storeys: crate::game::endless::MOST_STOREYS,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_tick_gives_about_100_hz() {
        assert_eq!(BASE_TICK_US, 222);
        assert_eq!(REFRESH_US, 9_990);
    }
}
