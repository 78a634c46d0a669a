//! BBC micro:bit v2: the hardware half (embassy-nrf wiring only).
//!
//! The `marble-microbit` firmware crate's board module (target
//! thumbv7em-none-eabihf). Every decision — sensor fault policy and its
//! down/up transitions, axis table, button combinations, scan timing, the
//! bus-clear sequence, the watchdog's rule — is in host-tested library code
//! ([`marble_rolling::input::sensor`], [`marble_rolling::input::buttons`],
//! [`marble_rolling::board::microbit`], [`marble_rolling::app`]), because
//! this half can only be tested on a board. What stays here moves bits
//! between those and the pins, and nothing here panics on a sensor or bus
//! error: every failure becomes a [`Fault`] for the supervisor.
//!
//! This file holds the LED matrix, the speaker, the records' flash and the
//! levels region; the accelerometer, its bus and the buttons are
//! [`crate::sensor`]'s, the System OFF sleep [`crate::sleep`]'s.

use embassy_nrf::gpio::{Level, Output, OutputDrive};
use embassy_nrf::pwm::{DutyCycle, Prescaler, SimpleConfig, SimplePwm};
use embassy_nrf::{peripherals, Peri};
use embassy_time::{Duration, Instant, Timer};
use embedded_storage_async::nor_flash;

use marble_rolling::app::{MatrixOutput, SoundOutput, REFRESH_HZ};
use marble_rolling::board::microbit::speaker::{self, SpeakerPwm};
use marble_rolling::board::microbit::{self as board, Heartbeats, Task};
#[cfg(doc)]
use marble_rolling::input::sensor::Fault;
use marble_rolling::matrix::ScanStep;
use marble_rolling::sound::{self, Sound};

/// RTC ticks per BCM base tick (4 → 109 Hz refresh; see the board module).
const RTC_TICKS_PER_BASE_TICK: u64 = board::rtc_ticks_per_base_tick(REFRESH_HZ) as u64;

/// One full refresh, in RTC ticks.
const REFRESH_TICKS: u64 = RTC_TICKS_PER_BASE_TICK
    * marble_rolling::matrix::Scanner::<{ board::WIDTH }, { board::HEIGHT }>::TICKS_PER_REFRESH
        as u64;

// ---------------------------------------------------------------------------
// LED matrix
// ---------------------------------------------------------------------------

/// The 5×5 LED matrix: rows driven high, columns pulled low to light.
pub struct Matrix {
    rows: [Output<'static>; board::HEIGHT],
    cols: [Output<'static>; board::WIDTH],
    lit_row: Option<usize>,
    deadline: Instant,
    heartbeats: &'static Heartbeats,
}

impl Matrix {
    /// Takes the row pins (top to bottom) and column pins (left to right);
    /// every scan step is the display task's heartbeat.
    pub fn new(
        rows: [Output<'static>; board::HEIGHT],
        cols: [Output<'static>; board::WIDTH],
        heartbeats: &'static Heartbeats,
    ) -> Self {
        Self {
            rows,
            cols,
            lit_row: None,
            deadline: Instant::now(),
            heartbeats,
        }
    }

    /// An output pin for a row (idle low = off).
    pub fn row_pin(pin: Peri<'static, impl embassy_nrf::gpio::Pin>) -> Output<'static> {
        Output::new(pin, Level::Low, OutputDrive::HighDrive)
    }

    /// An output pin for a column (idle high = off).
    pub fn col_pin(pin: Peri<'static, impl embassy_nrf::gpio::Pin>) -> Output<'static> {
        Output::new(pin, Level::High, OutputDrive::HighDrive)
    }
}

impl MatrixOutput<{ board::WIDTH }, { board::HEIGHT }> for Matrix {
    async fn show(&mut self, step: ScanStep) {
        // `show` runs inside app::display_task: reaching it proves the
        // display task runs (the watchdog waits for it).
        self.heartbeats.beat(Task::Display);
        let columns = step.columns;
        if self.lit_row != Some(step.row) {
            // Columns off before switching rows: no ghosting of the old row.
            for col in &mut self.cols {
                col.set_high();
            }
            for (y, row) in self.rows.iter_mut().enumerate() {
                row.set_level(if y == step.row {
                    Level::High
                } else {
                    Level::Low
                });
            }
            self.lit_row = Some(step.row);
        }
        for (x, col) in self.cols.iter_mut().enumerate() {
            col.set_level(if (columns >> x) & 1 != 0 {
                Level::Low
            } else {
                Level::High
            });
        }
        // Absolute deadlines: slice lengths do not accumulate wake-up latency.
        // After a long stall (debugger, flash), restart the schedule from now
        // instead of racing through the missed slices.
        let now = Instant::now();
        if now > self.deadline + Duration::from_ticks(REFRESH_TICKS) {
            self.deadline = now;
        }
        self.deadline += Duration::from_ticks(u64::from(step.ticks) * RTC_TICKS_PER_BASE_TICK);
        Timer::at(self.deadline).await;
    }
}

// ---------------------------------------------------------------------------
// Speaker
// ---------------------------------------------------------------------------

/// The speaker on P0.00, driven by PWM0: each [`sound::Note`] is a square
/// wave the PWM makes by itself while the task awaits the note's end, so
/// nothing busy-waits and the game never waits for a sound (its queue drops
/// what does not fit). The order of the PWM calls, and the duty for a note's
/// level, are [`board::speaker`]'s (host-tested against a model of the PWM).
///
/// The sound task waits for sounds ([`Heartbeats::waiting`]) except while it
/// plays, when each note is a heartbeat: a note whose timer never ended
/// would stop the watchdog's pets.
pub struct Speaker {
    pwm: SimplePwm<'static>,
    heartbeats: &'static Heartbeats,
}

impl Speaker {
    /// PWM0 on `pin`, silent; the sound task starts waiting for a sound.
    pub fn new(
        pwm: Peri<'static, peripherals::PWM0>,
        pin: Peri<'static, peripherals::P0_00>,
        heartbeats: &'static Heartbeats,
    ) -> Self {
        let mut config = SimpleConfig::default();
        // board::speaker::PWM_CLOCK_HZ: 16 MHz / 16.
        config.prescaler = Prescaler::Div16;
        let pwm = SimplePwm::new_1ch(pwm, pin, &config);
        pwm.disable();
        heartbeats.waiting(Task::Sound);
        Speaker { pwm, heartbeats }
    }
}

impl SpeakerPwm for Speaker {
    fn enable(&mut self) {
        self.pwm.enable();
    }

    fn disable(&mut self) {
        self.pwm.disable();
    }

    fn set_period(&mut self, hz: u32) {
        self.pwm.set_period(hz);
    }

    fn counter_top(&self) -> u16 {
        self.pwm.max_duty()
    }

    fn start_sequence(&mut self, compare: u16) {
        // embassy-nrf: the duty into the sequence's RAM, then SEQSTART.
        self.pwm.set_duty(0, DutyCycle::normal(compare));
    }
}

impl SoundOutput for Speaker {
    async fn play(&mut self, sound: Sound) {
        self.heartbeats.working(Task::Sound);
        for note in sound::notes(sound) {
            speaker::start_note(self, note);
            Timer::after_millis(u64::from(note.ms)).await;
            self.heartbeats.beat(Task::Sound);
        }
        speaker::silence(self);
        // Back to app::sound_task's queue, with no await before it.
        self.heartbeats.waiting(Task::Sound);
    }
}

// ---------------------------------------------------------------------------
// Records' flash: each operation a heartbeat
// ---------------------------------------------------------------------------

/// The records' NOR flash, telling the watchdog ([`Task::Records`]) when the
/// records task works: from the start of each flash operation to its end.
/// Between operations, and waiting for a win, the task has no other await
/// (`app::records_task`), so it counts as waiting; a flash operation that
/// never returned would stop the pets.
///
/// The ghosts' flash is the same type, unwatched (the game task beats at each
/// poll): one copy of the flash-map code serves both stores.
pub struct WatchedFlash<F> {
    flash: F,
    heartbeats: Option<&'static Heartbeats>,
}

impl<F> WatchedFlash<F> {
    /// `flash`, the records task waiting (also when no records task runs).
    pub fn new(flash: F, heartbeats: &'static Heartbeats) -> Self {
        heartbeats.waiting(Task::Records);
        Self {
            flash,
            heartbeats: Some(heartbeats),
        }
    }

    /// `flash`, no task's heartbeat.
    #[cfg(feature = "ghosts")]
    pub fn unwatched(flash: F) -> Self {
        Self {
            flash,
            heartbeats: None,
        }
    }

    /// Runs one flash operation as the records task's work.
    async fn watched<T>(&mut self, operation: impl AsyncFnOnce(&mut F) -> T) -> T {
        if let Some(heartbeats) = self.heartbeats {
            heartbeats.working(Task::Records);
        }
        let out = operation(&mut self.flash).await;
        if let Some(heartbeats) = self.heartbeats {
            heartbeats.waiting(Task::Records);
        }
        out
    }
}

impl<F: nor_flash::ErrorType> nor_flash::ErrorType for WatchedFlash<F> {
    type Error = F::Error;
}

impl<F: nor_flash::ReadNorFlash> nor_flash::ReadNorFlash for WatchedFlash<F> {
    const READ_SIZE: usize = F::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.watched(async |flash: &mut F| flash.read(offset, bytes).await)
            .await
    }

    fn capacity(&self) -> usize {
        self.flash.capacity()
    }
}

impl<F: nor_flash::NorFlash> nor_flash::NorFlash for WatchedFlash<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.watched(async |flash: &mut F| flash.erase(from, to).await)
            .await
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.watched(async |flash: &mut F| flash.write(offset, bytes).await)
            .await
    }
}

// ---------------------------------------------------------------------------
// The levels region
// ---------------------------------------------------------------------------

/// The levels region's bytes in flash
/// ([`marble_rolling::board::levels_region::V2`]), as the .hex put them
/// there: the caller reads them with `levels_region::at_boot`.
pub fn levels_region() -> &'static [u8] {
    use marble_rolling::board::levels_region::{SIZE, V2};
    // SAFETY: the region is SIZE bytes of on-chip flash, memory-mapped at
    // V2.start, always readable, aligned for bytes; memory.x keeps the
    // linker out of it and this firmware never erases or writes it (the
    // only flash it writes is the best times', board::RECORDS, pages apart),
    // so the bytes do not change while the slice lives.
    unsafe { core::slice::from_raw_parts(V2.start as usize as *const u8, SIZE) }
}

// ---------------------------------------------------------------------------
// The stack's high-water mark
// ---------------------------------------------------------------------------

/// Stack painting (`marble_board_runtime::stack`) on the nRF52833's RAM: the
/// free stack is painted at boot and the deepest word overwritten since is
/// logged whenever it went deeper, so that a board measures the stack that
/// nothing here can run (no nRF52 emulator).
pub mod stack {
    use marble_rolling::board::microbit::{RAM_BASE, STACK_PAINT};

    /// Paints the free stack. Call first thing in `main`.
    #[inline(always)]
    pub fn paint() {
        marble_board_runtime::stack::paint(RAM_BASE, STACK_PAINT);
    }

    /// The deepest stack use logged so far.
    pub struct Meter {
        logged: usize,
    }

    impl Meter {
        /// Nothing logged yet.
        pub const fn new() -> Self {
            Meter { logged: 0 }
        }

        /// Logs the high-water mark if it is deeper than the last one logged.
        /// Reads the stack region up to its deepest word (at most 112 KiB,
        /// under a millisecond): call it seldom.
        pub fn log_growth(&mut self) {
            let stack = marble_board_runtime::stack::high_water(RAM_BASE, STACK_PAINT);
            if stack.used > self.logged {
                self.logged = stack.used;
                defmt::info!(
                    "stack high-water mark: {=usize} of {=usize} bytes",
                    stack.used,
                    stack.size
                );
            }
        }
    }
}
