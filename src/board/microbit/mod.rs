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
//! A watchdog petted by one loop only proves that loop runs; a task parked
//! forever at an `await` (a display waiting on a dead timer, a game never
//! woken) would go unnoticed. So each task that must run bumps its own
//! counter in [`Heartbeats`], and the watchdog task pets only when
//! [`WatchdogGate`] has seen every counter move since the last pet. The
//! watchdog task itself runs in thread mode, so its pets also prove the
//! thread executor is not hogged.
//!
//! Some tasks wait for work that may not come for minutes (the sound task for
//! a sound, the records task for a win): a silent counter there is not a stall.
//! Such a task says when it waits ([`Heartbeats::waiting`]) and when it works
//! ([`Heartbeats::working`]); the gate excuses a waiting task and holds a
//! working one to the same rule as the others, so a sound whose timer never
//! ends, or a flash operation that never returns, stops the pets.

pub mod power_on;
pub mod sleep;
pub mod speaker;
#[cfg(feature = "shared-flash")]
pub mod storage;
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

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

/// How often the watchdog task checks the heartbeats (and pets when all
/// moved), ms. Ten checks per watchdog period: a task may be late for nine
/// of them (a sensor re-init takes ~50 ms) before the board resets.
pub const WATCHDOG_CHECK_MS: u64 = 100;

/// Fault supervision tuned for [`INPUT_PERIOD_MS`] and [`ACCEL_ODR_HZ`]: a
/// sample is due every 5 ms and the poll comes every 10 ms, so a poll without
/// new data is timing (a poll squeezed after slow work, the first poll after a
/// re-init); three in a row, about 30 ms or six sample periods without a
/// sample, is [`Fault::NoData`](crate::input::event::Fault::NoData).
pub const SUPERVISOR: SupervisorConfig = SupervisorConfig {
    not_ready_before_fault: 3,
    ..SupervisorConfig::DEFAULT
};

/// Internal I²C bus clock, kHz (the TWIM's `K400`).
pub const I2C_KHZ: u32 = 400;

/// Longest transfer the accelerometer driver makes: a register address
/// written, six data bytes read back (the three axes) — in bits on the wire,
/// including both address bytes, the ACK bits and the START/repeated
/// START/STOP conditions.
pub const LONGEST_TRANSFER_BITS: u32 = (2 + 1 + 6) * 9 + 3;

/// Deadline of one I²C transfer, ms. The longest transfer lasts
/// [`LONGEST_TRANSFER_BITS`] / [`I2C_KHZ`] ≈ 0.2 ms and the LSM303AGR does not
/// stretch the clock, so a transfer still running after 5 ms (over 20× that,
/// more than one RTC tick of timer granularity, half a poll period) is a hung
/// bus, not a slow one.
pub const I2C_TIMEOUT_MS: u64 = 5;

/// Size of the TWIM's RAM copy buffer, bytes.
///
/// nRF EasyDMA reads only RAM. embassy-nrf's `Twim` (`twim.rs`,
/// `Twim::set_tx_buffer`) copies a write buffer that is not in RAM into this
/// buffer, and refuses the transfer with `Error::RAMBufferTooSmall` (no bus
/// traffic at all) when the buffer is shorter than the write. lsm303agr 1.1
/// (`interface.rs`, `I2cInterface::read_register` and friends) reads a
/// register with `write_read(address, &[R::ADDR], …)` (`&[R::ADDR | 0x80]`
/// for multi-byte reads): a constant slice, which Rust promotes to a
/// `'static` in flash. With no copy buffer, every read — WHO_AM_I first —
/// failed on every board. The largest write any driver call makes is 2 bytes
/// (`write_accel_register`/`write_mag_register`: register address + value,
/// built on the stack, but the optimiser may fold such constants into flash
/// too), so 2 bytes cover every write wherever the compiler puts it.
///
/// The rule: every EasyDMA peripheral gets a copy buffer, sized for the
/// largest write its drivers make, unless every buffer it is given is
/// provably in RAM.
pub const TWIM_COPY_BUFFER_BYTES: usize = 2;

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

/// The ghosts' flash region (`marble_rolling::records::Ghosts`): the four 4 KiB
/// pages below the levels region, left out of `FLASH` in
/// `boards/microbit/memory.x`. Each level's best run is one item of at most a
/// page; a full region makes the oldest ghost give way.
pub const GHOSTS: core::ops::Range<u32> = 0x7_7000..0x7_B000;

/// The longest run the v2 records and keeps as a ghost, in bytes (the game
/// task's two buffers, `app::GhostKit`): about 7 s of the autopilot's play at
/// its 279 B/s, 4 s of a noisy sensor's at 489 B/s (docs/ghost.md).
pub const GHOST_BYTES: usize = 2048;

/// The largest generated maze the endless run plays on the v2
/// ([`crate::game::endless`]): 10 cells a side (21 tiles; the 5 × 5 view follows
/// the marble) on up to four storeys. Its slot keeps 444 B of tiles in the game
/// task's static RAM, and its text takes at most 1 992 B of stack while it is
/// parsed, between two levels (`cargo xtask size-report` has the figures).
pub const MAZE_REACH: crate::game::endless::Reach = crate::game::endless::Reach {
    size: 10,
    storeys: crate::game::endless::MOST_STOREYS,
};

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

// ---------------------------------------------------------------------------
// I²C bus clear (UM10204 §3.1.16)
// ---------------------------------------------------------------------------

/// SCL clocks the bus clear gives a slave to release SDA: a slave
/// transmitter stuck mid-byte has at most 8 data bits and the acknowledge
/// slot to go, where the master's silence (a NACK) makes it let go.
pub const BUS_CLEAR_MAX_CLOCKS: u8 = 9;

/// Half-periods SCL may stay low after being released (a slave stretching
/// the clock) before the bus clear gives up on it: 100 half-periods of
/// [`BUS_CLEAR_HALF_PERIOD_US`], 0.5 ms.
pub const BUS_CLEAR_STRETCH_LIMIT: u16 = 100;

/// Half of a bus-clear clock period, µs: 100 kHz, standard mode, which every
/// I²C slave accepts.
pub const BUS_CLEAR_HALF_PERIOD_US: u32 = 5;

/// The two I²C lines as open-drain GPIOs, for [`clear_bus`]. "High" is
/// released: the pull-ups raise the line unless a device holds it low.
pub trait BusLines {
    /// Releases SCL (`true`) or pulls it low (`false`).
    fn set_scl(&mut self, high: bool);
    /// Releases SDA (`true`) or pulls it low (`false`).
    fn set_sda(&mut self, high: bool);
    /// Whether SCL reads high.
    fn scl(&mut self) -> bool;
    /// Whether SDA reads high.
    fn sda(&mut self) -> bool;
    /// Waits half a clock period ([`BUS_CLEAR_HALF_PERIOD_US`]).
    fn half_period(&mut self);
}

/// How a [`clear_bus`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BusClear {
    /// SDA was high: a STOP alone freed the bus.
    Free,
    /// SDA went high after this many clocks (the STOP attempts a slave
    /// answered with a 0 bit included); a STOP followed.
    Released {
        /// Clocks given, 1 ..= [`BUS_CLEAR_MAX_CLOCKS`].
        clocks: u8,
    },
    /// SDA still low after [`BUS_CLEAR_MAX_CLOCKS`] clocks: only a power
    /// cycle of the slave helps.
    SdaStuck,
    /// SCL stays low beyond clock stretching: a slave or a short holds it.
    SclStuck,
}

impl BusClear {
    /// Whether the bus ended idle (both lines high after a STOP).
    pub const fn is_clear(&self) -> bool {
        matches!(self, BusClear::Free | BusClear::Released { .. })
    }
}

/// Releases SCL and waits while a slave stretches the clock (bounded).
fn release_scl<L: BusLines>(lines: &mut L) -> bool {
    lines.set_scl(true);
    for _ in 0..BUS_CLEAR_STRETCH_LIMIT {
        if lines.scl() {
            return true;
        }
        lines.half_period();
    }
    lines.scl()
}

/// The I²C bus clear (UM10204 §3.1.16, "Bus clear"): with both lines
/// released, clock SCL while SDA reads low — at most
/// [`BUS_CLEAR_MAX_CLOCKS`] times — until the slave holding SDA lets go, then
/// send a STOP so that every slave returns to idle.
///
/// SDA is sampled while SCL is high, where a slave keeps it stable. A STOP
/// is SDA pulled low while SCL is low, SCL released, SDA released: its SCL
/// pulse is itself a clock, so a slave transmitter stuck on a `1` bit may put
/// a `0` on SDA and swallow the STOP; then SDA is still low afterwards and
/// the clocking goes on, the failed attempt counted as one of the clocks.
/// The master never pulls SDA low while SCL is high, so the clear cannot
/// send a START. Bounded: at most [`BUS_CLEAR_MAX_CLOCKS`] + 1 SCL pulses
/// (the last a STOP) and [`BUS_CLEAR_STRETCH_LIMIT`] waits per release of
/// SCL. Pure: the board passes its pins as [`BusLines`].
pub fn clear_bus<L: BusLines>(lines: &mut L) -> BusClear {
    lines.set_sda(true);
    if !release_scl(lines) {
        return BusClear::SclStuck;
    }
    lines.half_period();
    let mut clocks: u8 = 0;
    loop {
        if lines.sda() {
            // STOP: SDA low while SCL is low, SCL high, then SDA high.
            lines.set_scl(false);
            lines.half_period();
            lines.set_sda(false);
            lines.half_period();
            let scl_released = release_scl(lines);
            lines.half_period();
            lines.set_sda(true);
            lines.half_period();
            if !scl_released {
                return BusClear::SclStuck;
            }
            if lines.sda() {
                return match clocks {
                    0 => BusClear::Free,
                    clocks => BusClear::Released { clocks },
                };
            }
            // A slave drove a 0 for that pulse and keeps SDA low.
            clocks = clocks.saturating_add(1);
        }
        if clocks >= BUS_CLEAR_MAX_CLOCKS {
            return BusClear::SdaStuck;
        }
        lines.set_scl(false);
        lines.half_period();
        if !release_scl(lines) {
            return BusClear::SclStuck;
        }
        lines.half_period();
        clocks += 1;
    }
}

// ---------------------------------------------------------------------------
// Watchdog: heartbeats of every task
// ---------------------------------------------------------------------------

/// A task the watchdog waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Task {
    /// Accelerometer and buttons (thread mode): beats once per poll.
    Input,
    /// The game (thread mode): beats each time it is polled — it awaits
    /// nothing but its frame ticker, so it is polled at the frame rate
    /// whether it plays, pauses for a downed sensor or shows a won level.
    Game,
    /// The LED matrix (interrupt executor): beats on every scan step.
    Display,
    /// The speaker (thread mode): waiting between sounds, beats at each note.
    Sound,
    /// The best times (thread mode): waiting between wins, beats at each
    /// flash operation.
    Records,
}

impl Task {
    /// Every task the watchdog waits for.
    pub const ALL: [Task; 5] = [
        Task::Input,
        Task::Game,
        Task::Display,
        Task::Sound,
        Task::Records,
    ];

    const fn index(self) -> usize {
        self as usize
    }
}

/// A set of [`Task`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tasks(u8);

impl Tasks {
    /// No task.
    pub const NONE: Tasks = Tasks(0);

    /// Whether `task` is in the set.
    pub const fn contains(self, task: Task) -> bool {
        self.0 & (1 << task.index()) != 0
    }

    /// Whether the set is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    const fn with(self, task: Task) -> Tasks {
        Tasks(self.0 | (1 << task.index()))
    }
}

/// One counter per [`Task`], and whether it waits for work, shared between
/// executors (a `static`).
///
/// Each counter has a single writer, its task, so a load and a store suffice
/// (no read-modify-write atomics: this builds for Cortex-M0 too). Only a
/// change matters, not the count.
#[derive(Debug, Default)]
pub struct Heartbeats {
    counts: [AtomicU32; Task::ALL.len()],
    waiting: [AtomicBool; Task::ALL.len()],
}

/// What the watchdog task reads of [`Heartbeats`] at one check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Snapshot {
    /// The counters, indexed like [`Task::ALL`].
    pub counts: [u32; Task::ALL.len()],
    /// The tasks waiting for work.
    pub waiting: Tasks,
}

impl From<[u32; Task::ALL.len()]> for Snapshot {
    /// Counters only, no task waiting.
    fn from(counts: [u32; Task::ALL.len()]) -> Self {
        Snapshot {
            counts,
            waiting: Tasks::NONE,
        }
    }
}

impl Heartbeats {
    /// No beat yet, no task waiting.
    pub const fn new() -> Self {
        Self {
            counts: [const { AtomicU32::new(0) }; Task::ALL.len()],
            waiting: [const { AtomicBool::new(false) }; Task::ALL.len()],
        }
    }

    /// `task` ran. Call it only from `task` itself.
    pub fn beat(&self, task: Task) {
        let count = &self.counts[task.index()];
        count.store(
            count.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }

    /// `task` waits for work (its queue is empty): excused until
    /// [`Heartbeats::working`]. Call it only from `task` itself.
    pub fn waiting(&self, task: Task) {
        self.waiting[task.index()].store(true, Ordering::Relaxed);
    }

    /// `task` has work: it beats, and must go on beating until it waits again.
    pub fn working(&self, task: Task) {
        self.waiting[task.index()].store(false, Ordering::Relaxed);
        self.beat(task);
    }

    /// The counters and the waiting tasks now.
    pub fn snapshot(&self) -> Snapshot {
        let mut waiting = Tasks::NONE;
        for task in Task::ALL {
            if self.waiting[task.index()].load(Ordering::Relaxed) {
                waiting = waiting.with(task);
            }
        }
        Snapshot {
            counts: core::array::from_fn(|i| self.counts[i].load(Ordering::Relaxed)),
            waiting,
        }
    }
}

/// What the watchdog task does after a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// Every task beat since the last pet: pet now.
    Pet,
    /// Do not pet: these tasks have not beaten since the last pet, for this
    /// many checks in a row (≥ 1).
    Wait {
        /// The tasks still to beat.
        stalled: Tasks,
        /// Checks without a pet.
        checks: u16,
    },
}

/// The watchdog task's rule: pet only when every task's counter moved since
/// the last pet, or the task waits for work. A working task parked forever
/// stops its counter, the pets stop, and the watchdog resets the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WatchdogGate {
    at_last_pet: [u32; Task::ALL.len()],
    checks_since_pet: u16,
}

impl WatchdogGate {
    /// Starts from the counters now (every task must beat, or wait, before
    /// the first pet).
    pub fn new(start: impl Into<Snapshot>) -> Self {
        Self {
            at_last_pet: start.into().counts,
            checks_since_pet: 0,
        }
    }

    /// One check with the heartbeats `now` ([`Heartbeats::snapshot`]).
    pub fn check(&mut self, now: impl Into<Snapshot>) -> Verdict {
        let now = now.into();
        let mut stalled = Tasks::NONE;
        for task in Task::ALL {
            if now.counts[task.index()] == self.at_last_pet[task.index()]
                && !now.waiting.contains(task)
            {
                stalled = stalled.with(task);
            }
        }
        if stalled.is_empty() {
            self.at_last_pet = now.counts;
            self.checks_since_pet = 0;
            Verdict::Pet
        } else {
            self.checks_since_pet = self.checks_since_pet.saturating_add(1);
            Verdict::Wait {
                stalled,
                checks: self.checks_since_pet,
            }
        }
    }
}
