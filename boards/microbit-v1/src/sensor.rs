//! The accelerometer on the internal I²C bus (TWI0, SCL P0.00, SDA P0.30):
//! found by `WHO_AM_I` (`board::microbit_v1::PROBES`), read through the
//! shared supervision (`TiltPipeline`), handed to the app as an
//! `app::TiltInput`.
//!
//! All three chips a v1 may carry: the MMA8653FC (v1.3, v1.3B) and the
//! FXOS8700CQ (v1.5) through the core's register driver
//! (`board::microbit_v1::nxp_driver`), the LSM303AGR (v1.5) through the
//! `lsm303agr` crate; each with its axis map (`board::microbit_v1::accel`).
//! The first probe finds logs `accel=<chip>`. In QEMU the TWI is a stub whose
//! reads return 0x5A, 0x5A, then 0x40: the MMA8653FC is found (its probe is
//! the first), then its status never flags new data and the supervision
//! decides (the sensor goes down; the demo counts it, a play waits).
//!
//! The bus is cleared (nine clocks and a STOP) before the first transfer and
//! after every failed one (`board::microbit_v1::twi::Recovering`).
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
use embedded_hal::i2c::{ErrorType, Operation};
use heapless::Deque;
use lsm303agr::Lsm303agr;
use marble_rolling::app::TiltInput;
use marble_rolling::board::microbit::{self as v2, Task};
use marble_rolling::board::microbit_v1::accel::{Accelerometer, NxpChip};
use marble_rolling::board::microbit_v1::nxp_driver;
use marble_rolling::board::microbit_v1::twi::{BusClear, Recovering, TwiError};
use marble_rolling::input::event::InputEvent;
use marble_rolling::input::lsm303;
use marble_rolling::input::sensor::{AccelMg, Action, Fault, Read, TiltPipeline};
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

impl BusClear for AsyncTwi {
    fn clear_bus(&mut self) {
        self.0.clear_bus();
    }
}

/// The bus the drivers use: cleared first and after every failure.
type Bus = Recovering<AsyncTwi>;

/// The LSM303AGR driver on the bus.
type Lsm = lsm303::Sensor<Bus>;

/// What is on the bus.
enum Chip {
    /// Nothing probed yet, or no probe answered: the bare bus.
    Unknown(Bus),
    /// The MMA8653FC or the FXOS8700CQ.
    Nxp(Bus, &'static NxpChip),
    /// The LSM303AGR.
    Lsm303agr(Lsm),
}

/// Brings up the chip: probes while none is known (and logs
/// `accel=<chip>` when one answers), then configures it.
async fn configure(chip: Chip) -> (Chip, Result<(), Fault>, Option<Accelerometer>) {
    let (chip, found) = match chip {
        Chip::Unknown(mut bus) => match nxp_driver::probe(&mut bus).await {
            Some(found) => {
                defmt::info!("accel={=str}", found.tag());
                let chip = match found.nxp() {
                    Some(nxp) => Chip::Nxp(bus, nxp),
                    None => Chip::Lsm303agr(Lsm303agr::new_with_i2c(bus)),
                };
                (chip, Some(found))
            }
            None => {
                defmt::warn!("accelerometer: none of MMA8653FC, FXOS8700CQ, LSM303AGR answered");
                return (Chip::Unknown(bus), Err(Fault::Implausible), None);
            }
        },
        chip => (chip, None),
    };
    match chip {
        Chip::Nxp(mut bus, nxp) => {
            let outcome = nxp_driver::configure(&mut bus, nxp).await;
            (Chip::Nxp(bus, nxp), outcome, found)
        }
        // Probing has just read WHO_AM_I.
        Chip::Lsm303agr(mut sensor) => {
            let outcome = lsm303::configure(&mut sensor).await;
            (Chip::Lsm303agr(sensor), outcome, found)
        }
        chip => (chip, Err(Fault::Implausible), found),
    }
}

/// One poll, sensor frame, milli-g.
async fn read(chip: &mut Chip) -> Read<AccelMg> {
    match chip {
        Chip::Nxp(bus, nxp) => nxp_driver::read(bus, nxp).await,
        Chip::Lsm303agr(sensor) => lsm303::read(sensor).await,
        Chip::Unknown(_) => Read::Failed(Fault::Implausible),
    }
}

/// The accelerometer as the app's tilt input, polled every
/// `INPUT_PERIOD_MS` (the v2's period and supervision; the chip's own axis
/// table from `board::microbit_v1::accel`).
pub struct Input {
    chip: Option<Chip>,
    pipeline: TiltPipeline,
    ticker: Option<Ticker>,
    pending: Deque<InputEvent, 2>,
    reinits: u32,
}

impl Input {
    /// The bus, nothing probed yet.
    pub fn new() -> Self {
        Self {
            chip: Some(Chip::Unknown(Recovering::new(AsyncTwi(Twi::new())))),
            pipeline: TiltPipeline::new(v2::AXIS_MAP, v2::SUPERVISOR),
            ticker: None,
            pending: Deque::new(),
            reinits: 0,
        }
    }

    /// Re-initialisations asked for by the supervision so far (the first
    /// bring-up not counted).
    pub fn reinits(&self) -> u32 {
        self.reinits
    }

    /// Faults the supervision counted so far.
    pub fn faults(&self) -> u32 {
        self.pipeline.supervisor().total_faults()
    }

    async fn reinit(&mut self) {
        let Some(chip) = self.chip.take() else {
            return;
        };
        let (chip, outcome, found) = configure(chip).await;
        self.chip = Some(chip);
        if let Some(found) = found {
            self.pipeline = TiltPipeline::new(found.axis_map(), v2::SUPERVISOR);
        }
        self.pipeline.reinit_done(outcome);
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
            self.reinits = self.reinits.wrapping_add(1);
            self.reinit().await;
        }
        if let Some(transition) = step.transition {
            defmt::warn!("accelerometer: {}", transition);
            let _ = self.pending.push_back(transition.event());
        }
        InputEvent::Tilt(lsm303::to_tilt(self.pipeline.tilt()))
    }
}
