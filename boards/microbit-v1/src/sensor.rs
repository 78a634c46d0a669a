//! The accelerometer on the internal I²C bus (TWI0, SCL P0.00, SDA P0.30),
//! as the app's `app::TiltInput`. The logic (probe by `WHO_AM_I`,
//! configure, poll, supervise, re-initialise, bus clear after a failure) is
//! the library's `board::microbit_v1::sensor::PollLoop`, host-tested on the
//! virtual chips; this file is its wiring: the TWI, the poll ticker, the
//! logs (`accel=<chip>` when the probe finds one), the events to the app.
//!
//! In QEMU the TWI is a stub, not a chip: its reads return 0x5A, 0x5A, 0x40
//! and then, in QEMU 7.2, a byte from past the end of its table (0x2E in
//! Debian's 7.2 build; later QEMUs repeat 0x40, the fix "Don't index off
//! end of twi_read_sequence[]"). The MMA8653FC is found (its probe comes
//! first), and with 0x2E its status flags new data at every poll and the
//! samples read 719, −719, 719 mg after the axis map: plausible, so the demo
//! plays on them with 0 re-inits and 0 faults (`cargo xtask
//! check-microbit-v1`). Where the stub repeats 0x40 instead, no new data is
//! ever flagged and the supervision takes the sensor down; the check accepts
//! either, by what the LEDs show.
//!
//! [`Twi`] is a minimal blocking driver for the nRF51's legacy TWI,
//! written on the PAC: embassy-nrf has no TWI driver for the nRF51 (only
//! the nRF52's EasyDMA TWIM) and no other crate drives it under embassy.
//! Every transfer has a deadline (a hung bus becomes [`TwiError::Timeout`],
//! never a hang); the driver's async API is served by [`AsyncTwi`], which
//! completes each transfer before returning (a transfer at 250 kHz is a few
//! hundred µs: it delays the input task only, the display runs on its own
//! interrupt).

use embassy_time::{Duration, Ticker};
use embedded_hal::i2c::{ErrorType, Operation};
use heapless::Deque;
use marble_rolling::app::TiltInput;
use marble_rolling::board::accel_link::INPUT_PERIOD_MS;
use marble_rolling::board::i2c::ClearBus;
use marble_rolling::board::microbit_v1::sensor::{PollLoop, Probed};
use marble_rolling::board::microbit_v1::twi::{Pause, TwiError};
use marble_rolling::board::watchdog::Task;
use marble_rolling::input::event::InputEvent;
use nrf_pac as pac;

use crate::hw::clock;

/// SCL of the internal bus.
const SCL_PIN: u32 = 0;
/// SDA of the internal bus.
const SDA_PIN: u32 = 30;
/// Deadline of one byte on the wire, µs (a byte at 250 kHz is 36 µs).
const BYTE_TIMEOUT_US: u64 = 1_000;
/// Deadline of a whole transfer, µs: the longest the drivers make (the
/// seven-byte burst with its register write, about 0.4 ms at 250 kHz) many
/// times over; a slave stretching the clock for longer is a stuck bus.
const TRANSFER_TIMEOUT_US: u64 = 5_000;
/// Half an SCL period of the bus clear, µs (100 kHz, the slowest mode every
/// slave follows).
const CLEAR_HALF_PERIOD_US: u64 = 5;

/// `PIN_CNF`: input buffer connected, pull-up, standard 0 / disconnect 1
/// (open drain); with bit 0 set, an output.
const OPEN_DRAIN: u32 = (3 << 2) | (6 << 8);

/// The nRF51 legacy TWI0, blocking (see the module doc).
pub struct Twi {
    /// When the transfer under way must be over, µs.
    deadline: u64,
}

impl Twi {
    /// Configures TWI0 on the internal bus at 250 kHz (the DAL's rate).
    pub fn new() -> Self {
        let twi = pac::TWI0;
        twi.enable().write_value(pac::twi::regs::Enable(0));
        Self::connect();
        twi.pselscl().write_value(SCL_PIN);
        twi.pselsda().write_value(SDA_PIN);
        twi.frequency()
            .write_value(pac::twi::regs::Frequency(0x0400_0000));
        twi.enable().write_value(pac::twi::regs::Enable(5));
        Twi { deadline: 0 }
    }

    /// Both lines as the TWI wants them: inputs, open drain, pulled up.
    fn connect() {
        for pin in [SCL_PIN, SDA_PIN] {
            pac::GPIO
                .pin_cnf(pin as usize)
                .write_value(pac::gpio::regs::PinCnf(OPEN_DRAIN));
        }
    }

    /// Busy-waits `us` µs.
    fn pause(us: u64) {
        let start = clock::now();
        while clock::now() - start < us {}
    }

    /// The bus clear: TWI off, SDA released, nine SCL clocks by hand (a
    /// slave in the middle of a byte shifts it out and lets SDA go), then a
    /// STOP (SDA rising while SCL is high); TWI back on.
    pub fn clear_bus(&mut self) {
        let twi = pac::TWI0;
        let gpio = pac::GPIO;
        let (scl, sda) = (1u32 << SCL_PIN, 1u32 << SDA_PIN);
        twi.enable().write_value(pac::twi::regs::Enable(0));
        gpio.outset()
            .write_value(pac::gpio::regs::Outset(scl | sda));
        for pin in [SCL_PIN, SDA_PIN] {
            gpio.pin_cnf(pin as usize)
                .write_value(pac::gpio::regs::PinCnf(OPEN_DRAIN | 1));
        }
        Self::pause(CLEAR_HALF_PERIOD_US);
        for _ in 0..9 {
            gpio.outclr().write_value(pac::gpio::regs::Outclr(scl));
            Self::pause(CLEAR_HALF_PERIOD_US);
            gpio.outset().write_value(pac::gpio::regs::Outset(scl));
            Self::pause(CLEAR_HALF_PERIOD_US);
        }
        // STOP: SDA low while SCL is low, SCL up, then SDA up.
        gpio.outclr().write_value(pac::gpio::regs::Outclr(scl));
        Self::pause(CLEAR_HALF_PERIOD_US);
        gpio.outclr().write_value(pac::gpio::regs::Outclr(sda));
        Self::pause(CLEAR_HALF_PERIOD_US);
        gpio.outset().write_value(pac::gpio::regs::Outset(scl));
        Self::pause(CLEAR_HALF_PERIOD_US);
        gpio.outset().write_value(pac::gpio::regs::Outset(sda));
        Self::pause(CLEAR_HALF_PERIOD_US);
        Self::connect();
        twi.events_error().write_value(0);
        twi.events_stopped().write_value(0);
        twi.enable().write_value(pac::twi::regs::Enable(5));
    }

    /// Waits for `event` (or an error) until the byte's deadline or the
    /// transfer's, whichever comes first.
    fn wait(&self, event: pac::common::Reg<u32, pac::common::RW>) -> Result<(), TwiError> {
        let twi = pac::TWI0;
        let start = clock::now();
        let deadline = (start + BYTE_TIMEOUT_US).min(self.deadline);
        loop {
            if twi.events_error().read() != 0 {
                twi.events_error().write_value(0);
                let source = twi.errorsrc().read().0;
                twi.errorsrc().write_value(pac::twi::regs::Errorsrc(source));
                twi.tasks_stop().write_value(1);
                return Err(if source & 0b010 != 0 {
                    TwiError::AddressNack
                } else if source & 0b100 != 0 {
                    TwiError::DataNack
                } else {
                    TwiError::Overrun
                });
            }
            if event.read() != 0 {
                event.write_value(0);
                return Ok(());
            }
            if clock::now() > deadline {
                twi.tasks_stop().write_value(1);
                return Err(TwiError::Timeout);
            }
        }
    }

    /// Writes `bytes`; ends with a STOP when `stop`.
    fn write(&mut self, address: u8, bytes: &[u8], stop: bool) -> Result<(), TwiError> {
        let twi = pac::TWI0;
        twi.shorts().write_value(pac::twi::regs::Shorts(0));
        twi.address()
            .write_value(pac::twi::regs::Address(u32::from(address)));
        twi.events_txdsent().write_value(0);
        twi.events_stopped().write_value(0);
        let mut bytes = bytes.iter();
        let Some(&first) = bytes.next() else {
            return Ok(());
        };
        twi.txd().write_value(pac::twi::regs::Txd(u32::from(first)));
        twi.tasks_starttx().write_value(1);
        self.wait(twi.events_txdsent())?;
        for &byte in bytes {
            twi.txd().write_value(pac::twi::regs::Txd(u32::from(byte)));
            self.wait(twi.events_txdsent())?;
        }
        if stop {
            twi.tasks_stop().write_value(1);
            self.wait(twi.events_stopped())?;
        }
        Ok(())
    }

    /// Reads into `buffer` (a repeated START if a write came before), then
    /// a STOP. Each byte is held by the BB → SUSPEND short until the previous
    /// one is read, the last one's BB → STOP ends the transfer (the nRF51
    /// reference manual's read sequence).
    fn read(&mut self, address: u8, buffer: &mut [u8]) -> Result<(), TwiError> {
        let twi = pac::TWI0;
        let last = buffer.len().saturating_sub(1);
        twi.address()
            .write_value(pac::twi::regs::Address(u32::from(address)));
        twi.events_rxdready().write_value(0);
        twi.events_stopped().write_value(0);
        let shorts = |index: usize| pac::twi::regs::Shorts(if index == last { 0b10 } else { 0b01 });
        twi.shorts().write_value(shorts(0));
        twi.tasks_startrx().write_value(1);
        for (index, byte) in buffer.iter_mut().enumerate() {
            self.wait(twi.events_rxdready())?;
            *byte = twi.rxd().read().0 as u8;
            if index < last {
                twi.shorts().write_value(shorts(index + 1));
                twi.tasks_resume().write_value(1);
            }
        }
        self.wait(twi.events_stopped())?;
        twi.shorts().write_value(pac::twi::regs::Shorts(0));
        Ok(())
    }
}

impl ErrorType for Twi {
    type Error = TwiError;
}

impl embedded_hal::i2c::I2c for Twi {
    fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), TwiError> {
        self.deadline = clock::now() + TRANSFER_TIMEOUT_US;
        let count = operations.len();
        for (index, operation) in operations.iter_mut().enumerate() {
            match operation {
                Operation::Write(bytes) => self.write(address, bytes, index + 1 == count)?,
                Operation::Read(buffer) => self.read(address, buffer)?,
            }
        }
        Ok(())
    }
}

/// [`Twi`] behind the async I²C trait the drivers take (the `lsm303agr`
/// crate's `async` feature is the workspace's: one API for every board).
pub struct AsyncTwi(Twi);

impl embedded_hal_async::i2c::ErrorType for AsyncTwi {
    type Error = TwiError;
}

impl embedded_hal_async::i2c::I2c for AsyncTwi {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [embedded_hal_async::i2c::Operation<'_>],
    ) -> Result<(), TwiError> {
        embedded_hal::i2c::I2c::transaction(&mut self.0, address, operations)
    }
}

impl ClearBus for AsyncTwi {
    fn clear_bus(&mut self) {
        self.0.clear_bus();
    }
}

impl Pause for AsyncTwi {
    /// Busy-waits, like every transfer of this blocking driver: the wait
    /// after an NXP chip's soft reset (1 ms) holds up the input task only.
    fn pause_us(&mut self, us: u32) {
        Twi::pause(u64::from(us));
    }
}

/// The accelerometer as the app's tilt input, polled every
/// `INPUT_PERIOD_MS` (the micro:bit's, `board::accel_link`) by the library's poll
/// loop (`board::microbit_v1::sensor::PollLoop`), which holds the logic; this
/// is its wiring: the TWI, the ticker, the logs, the events to the app.
pub struct Input {
    sensor: PollLoop<AsyncTwi>,
    ticker: Option<Ticker>,
    pending: Deque<InputEvent, 2>,
}

impl Input {
    /// The bus, nothing probed yet.
    pub fn new() -> Self {
        Self {
            sensor: PollLoop::new(AsyncTwi(Twi::new())),
            ticker: None,
            pending: Deque::new(),
        }
    }

    /// Re-initialisations asked for by the supervision so far (the first
    /// bring-up not counted).
    pub fn reinits(&self) -> u32 {
        self.sensor.reinits()
    }

    /// Faults the supervision counted so far.
    pub fn faults(&self) -> u32 {
        self.sensor.faults()
    }
}

/// The probe's outcome in the log (the demo's check looks for `accel=`).
fn log_probe(probed: Option<Probed>) {
    match probed {
        Some(Probed::Found(chip)) => defmt::info!("accel={=str}", chip.tag()),
        Some(Probed::NoneAnswered) => {
            defmt::warn!("accelerometer: none of MMA8653FC, LSM303AGR, FXOS8700CQ answered")
        }
        None => {}
    }
}

impl TiltInput for Input {
    async fn next_event(&mut self) -> InputEvent {
        crate::HEARTBEATS.beat(Task::Input);
        if let Some(event) = self.pending.pop_front() {
            return event;
        }
        match &mut self.ticker {
            Some(ticker) => ticker.next().await,
            None => {
                log_probe(self.sensor.bring_up().await);
                self.ticker = Some(Ticker::every(Duration::from_millis(INPUT_PERIOD_MS)));
            }
        }
        let polled = self.sensor.poll().await;
        log_probe(polled.probed);
        if let Some(transition) = polled.transition {
            defmt::warn!("accelerometer: {}", transition);
            let _ = self.pending.push_back(transition.event());
        }
        InputEvent::Tilt(self.sensor.tilt())
    }
}
