//! The accelerometer on the internal I²C bus (TWI0, SCL P0.00, SDA P0.30):
//! found by `WHO_AM_I` (`board::microbit_v1::PROBES`), read through the
//! shared supervision (`TiltPipeline`), handed to the app as an
//! `app::TiltInput`.
//!
//! Supported: the LSM303AGR (v1.5 boards), through the `lsm303agr` crate.
//! Detected but not supported yet: the MMA8653FC (v1.3/v1.3B) and the
//! FXOS8700CQ (v1.5) — the game then shows the sensor-down cross. In QEMU
//! the TWI is a stub whose reads return 0x5A, 0x5A, 0x40 and then garbage,
//! so no probe matches and the supervision takes the sensor down (the
//! game waits, as on a board with a broken sensor).
//!
//! [`Twi`] is a minimal blocking driver for the nRF51's legacy TWI,
//! written on the PAC: embassy-nrf has no TWI driver for the nRF51 (only
//! the nRF52's EasyDMA TWIM) and no other crate drives it under embassy.
//! Every transfer has a deadline (a hung bus becomes [`Fault::Timeout`],
//! never a hang); the driver's async API is served by [`AsyncTwi`], which
//! completes each transfer before returning (a transfer at 250 kHz is a few
//! hundred µs: it delays the input task only, the display runs on its own
//! interrupt).

use embassy_time::{Duration, Ticker};
use embedded_hal::i2c::{ErrorKind, ErrorType, NoAcknowledgeSource, Operation};
use heapless::Deque;
use lsm303agr::Lsm303agr;
use marble_rolling::app::TiltInput;
use marble_rolling::board::microbit as v2;
use marble_rolling::board::microbit_v1::{identify, Accelerometer, PROBES};
use marble_rolling::input::event::InputEvent;
use marble_rolling::input::lsm303::{self, BusFault};
use marble_rolling::input::sensor::{AccelMg, Action, Fault, Read, TiltPipeline};
use nrf_pac as pac;

use crate::hw::clock;

/// SCL of the internal bus.
const SCL_PIN: u32 = 0;
/// SDA of the internal bus.
const SDA_PIN: u32 = 30;
/// Deadline of one byte on the wire, µs (a byte at 250 kHz is 36 µs).
const BYTE_TIMEOUT_US: u64 = 1_000;

/// Why a TWI transfer failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum TwiError {
    /// No ACK to the address.
    AddressNack,
    /// No ACK to a data byte.
    DataNack,
    /// A received byte was overwritten.
    Overrun,
    /// No event before the deadline.
    Timeout,
}

impl embedded_hal::i2c::Error for TwiError {
    fn kind(&self) -> ErrorKind {
        match self {
            TwiError::AddressNack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
            TwiError::DataNack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data),
            TwiError::Overrun => ErrorKind::Overrun,
            TwiError::Timeout => ErrorKind::Other,
        }
    }
}

/// The nRF51 legacy TWI0, blocking (see the module doc).
pub struct Twi;

impl Twi {
    /// Configures TWI0 on the internal bus at 250 kHz (the DAL's rate).
    pub fn new() -> Self {
        let twi = pac::TWI0;
        twi.enable().write_value(pac::twi::regs::Enable(0));
        for pin in [SCL_PIN, SDA_PIN] {
            // Input, connected, pull-up, standard 0 / disconnect 1 (open drain).
            pac::GPIO
                .pin_cnf(pin as usize)
                .write_value(pac::gpio::regs::PinCnf((3 << 2) | (6 << 8)));
        }
        twi.pselscl().write_value(SCL_PIN);
        twi.pselsda().write_value(SDA_PIN);
        twi.frequency()
            .write_value(pac::twi::regs::Frequency(0x0400_0000));
        twi.enable().write_value(pac::twi::regs::Enable(5));
        Twi
    }

    /// Waits for `event` (or an error) until the byte deadline.
    fn wait(event: pac::common::Reg<u32, pac::common::RW>) -> Result<(), TwiError> {
        let twi = pac::TWI0;
        let start = clock::now();
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
            if clock::now() - start > BYTE_TIMEOUT_US {
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
        Self::wait(twi.events_txdsent())?;
        for &byte in bytes {
            twi.txd().write_value(pac::twi::regs::Txd(u32::from(byte)));
            Self::wait(twi.events_txdsent())?;
        }
        if stop {
            twi.tasks_stop().write_value(1);
            Self::wait(twi.events_stopped())?;
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
            Self::wait(twi.events_rxdready())?;
            *byte = twi.rxd().read().0 as u8;
            if index < last {
                twi.shorts().write_value(shorts(index + 1));
                twi.tasks_resume().write_value(1);
            }
        }
        Self::wait(twi.events_stopped())?;
        twi.shorts().write_value(pac::twi::regs::Shorts(0));
        Ok(())
    }

    /// One register read (a probe).
    fn read_register(&mut self, address: u8, register: u8) -> Result<u8, TwiError> {
        let mut byte = [0u8];
        self.write(address, &[register], false)?;
        self.read(address, &mut byte)?;
        Ok(byte[0])
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

/// [`Twi`] behind the async I²C trait the `lsm303agr` driver takes (its
/// `async` feature is the workspace's: one API for every board).
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

/// The LSM303AGR driver on the bus.
type Lsm = lsm303::Sensor<AsyncTwi>;

/// What is on the bus.
enum Chip {
    /// Nothing probed yet, or no probe answered: the bare bus.
    Unknown(Twi),
    /// A chip the firmware cannot drive (probed again at each re-init).
    Unsupported(Twi),
    /// The LSM303AGR.
    Lsm303agr(Lsm),
}

impl BusFault for TwiError {
    fn fault(&self) -> Fault {
        match self {
            TwiError::Timeout => Fault::Timeout,
            _ => Fault::Bus,
        }
    }
}

/// Probes the bus for each accelerometer a v1 may carry.
fn probe(twi: &mut Twi) -> Option<Accelerometer> {
    PROBES.iter().find_map(|probe| {
        let read = twi.read_register(probe.address, probe.register).ok();
        identify(probe, read)
    })
}

/// Brings up the chip: probes while none is known, configures the
/// LSM303AGR (200 Hz, high resolution, block data update).
async fn configure(chip: Chip) -> (Chip, Result<(), Fault>) {
    let chip = match chip {
        Chip::Unknown(mut twi) | Chip::Unsupported(mut twi) => match probe(&mut twi) {
            Some(Accelerometer::Lsm303agr) => {
                defmt::info!("accelerometer: LSM303AGR");
                Chip::Lsm303agr(Lsm303agr::new_with_i2c(AsyncTwi(twi)))
            }
            Some(other) => {
                defmt::warn!(
                    "accelerometer: {=str} found, not supported yet",
                    other.name()
                );
                return (Chip::Unsupported(twi), Err(Fault::Implausible));
            }
            None => {
                defmt::warn!("accelerometer: none of MMA8653FC, LSM303AGR, FXOS8700CQ answered");
                return (Chip::Unknown(twi), Err(Fault::Implausible));
            }
        },
        chip => chip,
    };
    let Chip::Lsm303agr(mut sensor) = chip else {
        return (chip, Err(Fault::Implausible));
    };
    // Probing has just read WHO_AM_I.
    let outcome = lsm303::configure(&mut sensor).await;
    (Chip::Lsm303agr(sensor), outcome)
}

/// One poll, sensor frame, milli-g.
async fn read(chip: &mut Chip) -> Read<AccelMg> {
    match chip {
        Chip::Lsm303agr(sensor) => lsm303::read(sensor).await,
        _ => Read::Failed(Fault::Implausible),
    }
}

/// The accelerometer as the app's tilt input, polled every
/// `INPUT_PERIOD_MS` (the v2's period, supervision and axis table; the
/// LSM303AGR's mounting on the v1.5 is assumed to be the v2's — not checked
/// on a board).
pub struct Input {
    chip: Option<Chip>,
    pipeline: TiltPipeline,
    ticker: Option<Ticker>,
    pending: Deque<InputEvent, 2>,
}

impl Input {
    /// The bus, nothing probed yet.
    pub fn new() -> Self {
        Self {
            chip: Some(Chip::Unknown(Twi::new())),
            pipeline: TiltPipeline::new(v2::AXIS_MAP, v2::SUPERVISOR),
            ticker: None,
            pending: Deque::new(),
        }
    }

    async fn reinit(&mut self) {
        let Some(chip) = self.chip.take() else {
            return;
        };
        let (chip, outcome) = configure(chip).await;
        self.chip = Some(chip);
        self.pipeline.reinit_done(outcome);
    }
}

impl TiltInput for Input {
    async fn next_event(&mut self) -> InputEvent {
        if let Some(event) = self.pending.pop_front() {
            return event;
        }
        match &mut self.ticker {
            Some(ticker) => ticker.next().await,
            None => {
                self.reinit().await;
                self.ticker = Some(Ticker::every(Duration::from_millis(v2::INPUT_PERIOD_MS)));
            }
        }
        let reading = match &mut self.chip {
            Some(chip) => read(chip).await,
            None => Read::Failed(Fault::Bus),
        };
        let step = self.pipeline.feed(reading);
        if let Action::Reinit = step.action {
            self.reinit().await;
        }
        if let Some(transition) = step.transition {
            defmt::warn!("accelerometer: {}", transition);
            let _ = self.pending.push_back(transition.event());
        }
        InputEvent::Tilt(lsm303::to_tilt(self.pipeline.tilt()))
    }
}
