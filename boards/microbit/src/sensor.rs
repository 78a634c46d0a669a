//! The accelerometer and the buttons as the app's tilt input: the internal
//! I²C bus under the boards' bus-clear rule, the LSM303AGR on it, and the
//! poll that feeds the pipeline (embassy-nrf wiring only; the decisions are
//! the library's, see [`crate::hw`]).
//!
//! The I²C bus gets particular care ([`Bus`]): a transfer that never ends
//! would park the input task until the watchdog reset, so each one has a
//! deadline, and a failed one is followed by the I²C bus clear.

use embassy_nrf::gpio::{AnyPin, Flex, Input, Level, OutputDrive, Pull};
use embassy_nrf::twim::{self, Twim};
use embassy_nrf::{peripherals, Peri};
use embassy_time::{with_timeout, Duration, Instant, Ticker, Timer};
use embedded_hal_async::i2c::{ErrorType, I2c, Operation};
use heapless::Deque;

use marble_rolling::app::TiltInput;
use marble_rolling::board::i2c::{ClearBus, Recovering};
use marble_rolling::board::microbit::{self as board, BusLines, Heartbeats, Task};
use marble_rolling::input::buttons::{ButtonEvent, Buttons};
use marble_rolling::input::event::{Command, InputEvent};
use marble_rolling::input::lsm303::{self, BusFault};
use marble_rolling::input::pacing;
use marble_rolling::input::sensor::{Action, Fault, Read, TiltPipeline};

use crate::sleep::{system_off, SLEEP};

/// CPU cycles per microsecond (64 MHz), for the bus clear's busy waits.
const CYCLES_PER_US: u32 = 64;

// ---------------------------------------------------------------------------
// I²C: the TWIM with a deadline, cleared by the boards' rule
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
/// `I2c`: [`TimedTwim`] under the boards' bus-clear rule ([`Recovering`]), a
/// clear before the first transfer and after any that failed on the wire.
pub type Bus = Recovering<TimedTwim>;

/// [`Bus`] on TWIM0 and the bus pins.
pub fn bus(
    twim: Peri<'static, peripherals::TWISPI0>,
    sda: Peri<'static, AnyPin>,
    scl: Peri<'static, AnyPin>,
) -> Bus {
    Recovering::new(TimedTwim::new(twim, sda, scl))
}

/// TWIM0: every transfer on a fresh `Twim` with a copy buffer, under a
/// deadline; the bus clear on its pins as GPIOs.
///
/// The `Twim` lives for one transfer only: it borrows the peripheral and the
/// pins from here, so dropping it hands them back for the bus clear and the
/// next transfer starts from a freshly configured TWIM — without `unsafe`
/// stealing of peripherals. Creating one is a few register writes.
pub struct TimedTwim {
    twim: Peri<'static, peripherals::TWISPI0>,
    sda: Peri<'static, AnyPin>,
    scl: Peri<'static, AnyPin>,
    /// The TWIM's RAM copy buffer for writes from flash
    /// ([`board::TWIM_COPY_BUFFER_BYTES`] says why and how big). A field
    /// borrowed mutably, so it is in RAM (the input task's static storage),
    /// never in flash.
    copy: [u8; board::TWIM_COPY_BUFFER_BYTES],
    /// Bus clears run, for the log.
    clears: u32,
}

impl TimedTwim {
    fn new(
        twim: Peri<'static, peripherals::TWISPI0>,
        sda: Peri<'static, AnyPin>,
        scl: Peri<'static, AnyPin>,
    ) -> Self {
        Self {
            twim,
            sda,
            scl,
            copy: [0; board::TWIM_COPY_BUFFER_BYTES],
            clears: 0,
        }
    }
}

impl ClearBus for TimedTwim {
    /// Runs the bus clear on the pins as open-drain GPIOs (the TWIM must be
    /// dropped: it is, outside [`TimedTwim::transaction`]).
    fn clear_bus(&mut self) {
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
    }

    /// A timeout, or a TWIM error from the wire rather than from the driver
    /// refusing the buffers before any traffic.
    fn on_the_wire(error: &BusError) -> bool {
        !matches!(
            error,
            BusError::Twim(
                twim::Error::TxBufferTooLong
                    | twim::Error::RxBufferTooLong
                    | twim::Error::RAMBufferTooSmall
            )
        )
    }
}

impl ErrorType for TimedTwim {
    type Error = BusError;
}

impl I2c for TimedTwim {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), BusError> {
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
                Err(BusError::Twim(e))
            }
            Err(_) => {
                defmt::warn!("i2c: transfer to {=u8:#x} timed out", address);
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
        let tilt = InputEvent::Tilt(self.pipeline.tilt());
        let _ = self.pending.push_back(tilt);
        self.pending.pop_front().unwrap_or(tilt)
    }
}
