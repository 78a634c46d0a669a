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
//! The I²C bus gets particular care ([`Bus`]): a transfer that never ends
//! would park the input task until the watchdog reset, so each one has a
//! deadline, and a failed one is followed by the I²C bus clear.

use embassy_nrf::gpio::{AnyPin, Flex, Input, Level, Output, OutputDrive, Pull};
use embassy_nrf::pac;
use embassy_nrf::pac::gpio::vals::Sense;
use embassy_nrf::pwm::{DutyCycle, Prescaler, SimpleConfig, SimplePwm};
use embassy_nrf::twim::{self, Twim};
use embassy_nrf::{peripherals, Peri};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{with_timeout, Duration, Instant, Ticker, Timer};
use embedded_hal_async::i2c::{ErrorType, I2c, Operation};
use embedded_storage_async::nor_flash;
use heapless::Deque;

use marble_rolling::app::{Links, MatrixOutput, SoundOutput, TiltInput, REFRESH_HZ};
use marble_rolling::board::microbit::sleep;
use marble_rolling::board::microbit::speaker::{self, SpeakerPwm};
use marble_rolling::board::microbit::{self as board, BusClear, BusLines, Heartbeats, Task};
use marble_rolling::input::buttons::{ButtonEvent, Buttons};
use marble_rolling::input::event::{Command, InputEvent};
use marble_rolling::input::lsm303::{self, BusFault};
use marble_rolling::input::pacing;
use marble_rolling::input::sensor::{Action, Fault, Read, TiltPipeline};
use marble_rolling::matrix::{Frame, ScanStep};
use marble_rolling::sound::{self, Sound};

/// RTC ticks per BCM base tick (4 → 109 Hz refresh; see the board module).
const RTC_TICKS_PER_BASE_TICK: u64 = board::rtc_ticks_per_base_tick(REFRESH_HZ) as u64;

/// One full refresh, in RTC ticks.
const REFRESH_TICKS: u64 = RTC_TICKS_PER_BASE_TICK
    * marble_rolling::matrix::Scanner::<{ board::WIDTH }, { board::HEIGHT }>::TICKS_PER_REFRESH
        as u64;

/// CPU cycles per microsecond (64 MHz), for the bus clear's busy waits.
const CYCLES_PER_US: u32 = 64;

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
// I²C: the TWIM with a deadline and a bus clear
// ---------------------------------------------------------------------------

/// I²C configuration of the internal bus ([`board::I2C_KHZ`]; the board has
/// external pull-ups).
pub fn twim_config() -> twim::Config {
    let mut config = twim::Config::default();
    config.frequency = twim::Frequency::K400;
    config
}

/// Why a transfer on [`Bus`] failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum BusError {
    /// The TWIM reported an error.
    Twim(twim::Error),
    /// The transfer did not finish within [`board::I2C_TIMEOUT_MS`]; the bus
    /// was cleared.
    Timeout,
}

impl embedded_hal_async::i2c::Error for BusError {
    fn kind(&self) -> embedded_hal_async::i2c::ErrorKind {
        match self {
            BusError::Twim(e) => embedded_hal_async::i2c::Error::kind(e),
            BusError::Timeout => embedded_hal_async::i2c::ErrorKind::Other,
        }
    }
}

/// The internal I²C bus (TWIM0, SDA P0.16, SCL P0.08) as the sensor driver's
/// `I2c`: every transfer on a fresh `Twim` with a copy buffer, under a
/// deadline, and a bus clear after any transfer that failed on the wire.
///
/// The `Twim` lives for one transfer only: it borrows the peripheral and the
/// pins from here, so dropping it hands them back for the bus clear and the
/// next transfer starts from a freshly configured TWIM — without `unsafe`
/// stealing of peripherals. Creating one is a few register writes.
pub struct Bus {
    twim: Peri<'static, peripherals::TWISPI0>,
    sda: Peri<'static, AnyPin>,
    scl: Peri<'static, AnyPin>,
    /// The TWIM's RAM copy buffer for writes from flash
    /// ([`board::TWIM_COPY_BUFFER_BYTES`] says why and how big). A field
    /// borrowed mutably, so it is in RAM (the input task's static storage),
    /// never in flash.
    copy: [u8; board::TWIM_COPY_BUFFER_BYTES],
    /// Clear the bus before the next transfer (set at boot: a slave may be
    /// stuck mid-read from before a reset).
    clear_first: bool,
    /// Bus clears run, for the log.
    clears: u32,
}

impl Bus {
    /// Takes TWIM0 and the bus pins.
    pub fn new(
        twim: Peri<'static, peripherals::TWISPI0>,
        sda: Peri<'static, AnyPin>,
        scl: Peri<'static, AnyPin>,
    ) -> Self {
        Self {
            twim,
            sda,
            scl,
            copy: [0; board::TWIM_COPY_BUFFER_BYTES],
            clear_first: true,
            clears: 0,
        }
    }

    /// Runs the bus clear on the pins as open-drain GPIOs (the TWIM must be
    /// dropped: it is, outside [`Bus::transaction`]).
    fn clear(&mut self) -> BusClear {
        let outcome = board::clear_bus(&mut GpioLines::new(
            self.sda.reborrow(),
            self.scl.reborrow(),
        ));
        self.clears = self.clears.saturating_add(1);
        if outcome.is_clear() {
            defmt::debug!("i2c: bus clear #{}: {}", self.clears, outcome);
        } else {
            defmt::warn!("i2c: bus clear #{}: {}", self.clears, outcome);
        }
        outcome
    }
}

/// Whether a TWIM error came from the wire (so the bus may be stuck), rather
/// than from the driver refusing the buffers before any traffic.
fn on_the_wire(e: twim::Error) -> bool {
    !matches!(
        e,
        twim::Error::TxBufferTooLong
            | twim::Error::RxBufferTooLong
            | twim::Error::RAMBufferTooSmall
    )
}

impl ErrorType for Bus {
    type Error = BusError;
}

impl I2c for Bus {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), BusError> {
        if self.clear_first {
            self.clear_first = false;
            self.clear();
        }
        let mut twim = Twim::new(
            self.twim.reborrow(),
            crate::Irqs,
            self.sda.reborrow(),
            self.scl.reborrow(),
            twim_config(),
            &mut self.copy,
        );
        let outcome = with_timeout(
            Duration::from_millis(board::I2C_TIMEOUT_MS),
            twim.transaction(address, operations),
        )
        .await;
        // Dropping the Twim disables TWIM0 and with it its EasyDMA, here,
        // while `operations` (the DMA's buffers) are still borrowed: a timed
        // out transfer cannot write into memory that is gone.
        drop(twim);
        match outcome {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => {
                if e == twim::Error::RAMBufferTooSmall {
                    defmt::error!(
                        "i2c: a write from flash exceeds the {} B copy buffer",
                        board::TWIM_COPY_BUFFER_BYTES
                    );
                }
                if on_the_wire(e) {
                    self.clear();
                }
                Err(BusError::Twim(e))
            }
            Err(_) => {
                defmt::warn!("i2c: transfer to {=u8:#x} timed out", address);
                self.clear();
                Err(BusError::Timeout)
            }
        }
    }
}

/// The bus pins as open-drain GPIOs with pull-ups, for [`board::clear_bus`].
struct GpioLines<'a> {
    sda: Flex<'a>,
    scl: Flex<'a>,
}

impl<'a> GpioLines<'a> {
    fn new(sda: Peri<'a, AnyPin>, scl: Peri<'a, AnyPin>) -> Self {
        let mut sda = Flex::new(sda);
        let mut scl = Flex::new(scl);
        for pin in [&mut sda, &mut scl] {
            // Released before the output is enabled: no glitch on the bus.
            pin.set_high();
            pin.set_as_input_output(Pull::Up, OutputDrive::Standard0Disconnect1);
        }
        Self { sda, scl }
    }
}

impl BusLines for GpioLines<'_> {
    fn set_scl(&mut self, high: bool) {
        self.scl.set_level(Level::from(high));
    }

    fn set_sda(&mut self, high: bool) {
        self.sda.set_level(Level::from(high));
    }

    fn scl(&mut self) -> bool {
        self.scl.is_high()
    }

    fn sda(&mut self) -> bool {
        self.sda.is_high()
    }

    fn half_period(&mut self) {
        cortex_m::asm::delay(board::BUS_CLEAR_HALF_PERIOD_US * CYCLES_PER_US);
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
// Accelerometer
// ---------------------------------------------------------------------------

/// The LSM303AGR on the internal bus (address 0x19 for the accelerometer).
pub type Sensor = lsm303::Sensor<Bus>;

impl BusFault for BusError {
    fn fault(&self) -> Fault {
        match self {
            BusError::Timeout => Fault::Timeout,
            BusError::Twim(_) => Fault::Bus,
        }
    }
}

// ---------------------------------------------------------------------------
// Input: accelerometer + buttons → app::TiltInput
// ---------------------------------------------------------------------------

/// Polls the accelerometer and buttons every [`board::INPUT_PERIOD_MS`] and
/// produces the app's tilt and command events, and the sensor's down/up
/// transitions as the pipeline reports them.
pub struct MicrobitInput {
    sensor: Sensor,
    button_a: Input<'static>,
    button_b: Input<'static>,
    buttons: Buttons,
    pipeline: TiltPipeline,
    ticker: Option<Ticker>,
    /// When the sensor was last polled (`input::pacing`).
    last_poll: Option<Instant>,
    /// Events of this poll still to hand out, in order.
    pending: Deque<InputEvent, 4>,
    heartbeats: &'static Heartbeats,
}

impl MicrobitInput {
    /// Every poll is the input task's heartbeat in `heartbeats`.
    pub fn new(
        sensor: Sensor,
        button_a: Input<'static>,
        button_b: Input<'static>,
        heartbeats: &'static Heartbeats,
    ) -> Self {
        Self {
            sensor,
            button_a,
            button_b,
            buttons: Buttons::new(board::BUTTONS),
            pipeline: TiltPipeline::new(board::AXIS_MAP, board::SUPERVISOR),
            ticker: None,
            last_poll: None,
            pending: Deque::new(),
            heartbeats,
        }
    }

    /// A button input (active low; the board has pull-ups, the internal one
    /// is added for safety).
    pub fn button_pin(pin: Peri<'static, impl embassy_nrf::gpio::Pin>) -> Input<'static> {
        Input::new(pin, Pull::Up)
    }

    /// (Re)configures the sensor and tells the pipeline how it went
    /// ([`lsm303::reinit`]).
    async fn reinit(&mut self) {
        let outcome = lsm303::reinit(&mut self.sensor, &mut self.pipeline).await;
        reinit_failed(outcome);
    }

    /// Powers the accelerometer down (System OFF ahead): a bus error is
    /// logged and ignored, the board sleeps anyway.
    pub async fn power_down(&mut self) {
        if let Err(fault) = lsm303::power_down(&mut self.sensor).await {
            defmt::warn!("accelerometer: power-down failed: {}", fault);
        }
    }

    /// One polling period: buttons, then the sensor through the pipeline.
    async fn poll(&mut self) -> Option<Command> {
        let command = match self
            .buttons
            .update(self.button_a.is_low(), self.button_b.is_low())
        {
            Some(ButtonEvent::NextLevel) => Some(Command::NextLevel),
            Some(ButtonEvent::Restart) => Some(Command::Restart),
            Some(ButtonEvent::Calibrate) => Some(Command::Calibrate),
            Some(ButtonEvent::ToggleMute) => Some(Command::ToggleMute),
            None => None,
        };
        let polled = lsm303::poll(
            &mut self.sensor,
            &mut self.pipeline,
            |read, step| match step.action {
                Action::Use(_) | Action::ShowFault => {}
                Action::KeepLast(_) => {
                    if let Read::Failed(fault) = read {
                        defmt::debug!("accelerometer: {}", fault);
                    }
                }
                Action::Reinit => defmt::warn!("accelerometer: re-initialising"),
            },
        )
        .await;
        let step = polled.step;
        if let Some(outcome) = polled.reinit {
            reinit_failed(outcome);
        }
        if let Some(transition) = step.transition {
            defmt::warn!("accelerometer: {}", transition);
            let _ = self.pending.push_back(transition.event());
        }
        command
    }
}

/// Logs a failed (re)init.
fn reinit_failed(outcome: Result<(), Fault>) {
    if let Err(fault) = outcome {
        defmt::warn!("accelerometer: (re)init failed: {}", fault);
    }
}

impl TiltInput for MicrobitInput {
    async fn next_event(&mut self) -> InputEvent {
        if let Some(event) = self.pending.pop_front() {
            return event;
        }
        let period = Duration::from_millis(board::INPUT_PERIOD_MS);
        match &mut self.ticker {
            Some(ticker) => ticker.next().await,
            None => {
                // First call: the chip's boot time since power-up (the
                // firmware may be here sooner), then bring the sensor up (a
                // failure is handled by the supervisor like any other).
                Timer::at(Instant::from_millis(board::ACCEL_BOOT_MS)).await;
                self.reinit().await;
                self.ticker = Some(Ticker::every(period));
            }
        }
        self.heartbeats.beat(Task::Input);
        if let Some(level) = SLEEP.try_take() {
            self.power_down().await;
            system_off(&crate::LINKS, level).await;
        }
        let started = Instant::now();
        // A tick after a stall (a flash page erase holds the CPU some 85 ms)
        // polls once and starts the period over (`input::pacing`).
        let late = self.last_poll.is_some_and(|last| {
            pacing::late(last.as_micros(), started.as_micros(), period.as_micros())
        });
        self.last_poll = Some(started);
        let command = self.poll().await;
        if late || Instant::now() >= started + period {
            // Slow work (a re-init, a timed-out transfer and its bus clear):
            // the ticker would fire every missed period back to back, polling
            // a sensor with no new sample yet and squeezing the button
            // debounce. Start the period over instead.
            if let Some(ticker) = &mut self.ticker {
                ticker.reset();
            }
        }
        if let Some(command) = command {
            let _ = self.pending.push_back(InputEvent::Command(command));
        }
        let tilt = InputEvent::Tilt(lsm303::to_tilt(self.pipeline.tilt()));
        let _ = self.pending.push_back(tilt);
        self.pending.pop_front().unwrap_or(tilt)
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
pub struct WatchedFlash<F> {
    flash: F,
    heartbeats: &'static Heartbeats,
}

impl<F> WatchedFlash<F> {
    /// `flash`, the records task waiting (also when no records task runs).
    pub fn new(flash: F, heartbeats: &'static Heartbeats) -> Self {
        heartbeats.waiting(Task::Records);
        Self { flash, heartbeats }
    }

    /// Runs one flash operation as the records task's work.
    async fn watched<T>(&mut self, operation: impl AsyncFnOnce(&mut F) -> T) -> T {
        self.heartbeats.working(Task::Records);
        let out = operation(&mut self.flash).await;
        self.heartbeats.waiting(Task::Records);
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
// Idle sleep: System OFF
// ---------------------------------------------------------------------------

/// The level to start at: the one the toy fell asleep on when this reset is
/// the wake-up from [`system_off`], else the first. Clears the marker.
pub fn level_after_reset() -> u8 {
    let level = board::level_after_reset(pac::POWER.gpregret().read().gpregret());
    pac::POWER.gpregret().write(|w| w.set_gpregret(0));
    level
}

/// Port 0, the GPIOTE and POWER as [`sleep::SleepRegisters`].
struct NrfSleep;

impl sleep::SleepRegisters for NrfSleep {
    fn mask_interrupts(&mut self) {
        cortex_m::interrupt::disable();
    }

    fn disable_port_interrupt(&mut self) {
        pac::GPIOTE.intenclr(0).write(|w| w.set_port(true));
        pac::GPIOTE.events_port(0).write_value(0);
    }

    fn sense_low(&mut self, pin: usize) {
        pac::P0.pin_cnf(pin).modify(|w| w.set_sense(Sense::Low));
    }

    fn clear_latch(&mut self, bits: u32) {
        pac::P0.latch().write(|w| w.0 = bits);
    }

    fn system_off(&mut self) {
        pac::POWER.systemoff().write(|w| w.set_systemoff(true));
    }
}

/// The game task's request to sleep on a level, taken by the input task (which
/// owns the accelerometer and powers it down first): [`request_sleep`].
static SLEEP: Signal<CriticalSectionRawMutex, u8> = Signal::new();

/// Asks the input task to put the board in System OFF on `level`; the caller
/// (the game task) then waits forever. Should the input task never take it,
/// the game task's silence makes the watchdog reset the board.
pub async fn request_sleep(level: u8) -> ! {
    SLEEP.signal(level);
    core::future::pending().await
}

/// Sleeps in System OFF, the nRF52833's lowest state that keeps the flash
/// (the records) and GPREGRET: the display dark (its last frame blank for a
/// full refresh), level `level` kept in GPREGRET, buttons A and B armed
/// (`board::sleep::WAKE_PINS`) to wake it on a press. The wake-up is a reset
/// ([`level_after_reset`]), and the input task's first poll initialises the
/// accelerometer again. Called by the input task, the accelerometer already
/// powered down.
///
/// The register writes are [`board::sleep::enter_system_off`]'s, in the
/// order that wins the SENSE race against embassy-nrf's GPIOTE handler (that
/// module says why; `tests/microbit_sleep.rs` checks it).
async fn system_off(links: &'static Links<{ board::WIDTH }, { board::HEIGHT }>, level: u8) -> ! {
    links.frames.signal(Frame::new());
    // Two refreshes at 109 Hz: the blank frame is on, every row off.
    embassy_time::Timer::after_millis(25).await;
    pac::POWER
        .gpregret()
        .write(|w| w.set_gpregret(board::sleep_marker(level)));
    defmt::info!("System OFF on level {=u8}: a button wakes", level + 1);
    sleep::enter_system_off(&mut NrfSleep);
    // Under a debugger System OFF is only emulated, and the core runs on.
    loop {
        cortex_m::asm::wfe();
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
