//! The v1's I²C bus as the sensor stack sees it: the TWI driver's errors
//! ([`TwiError`], what the supervisor makes of them) and the bus-clear rule
//! ([`Recovering`]): a reset in the middle of a read (a reflash, a brown-out)
//! can leave the accelerometer holding SDA low, waiting for clocks that never
//! come; nine clocks and a STOP free it (the I²C specification's bus clear,
//! UM10204 §3.1.16). The firmware clears the bus before its first transfer
//! and, through [`Recovering`], after every failed one. Pure logic, so the
//! host tests run the rule against a virtual bus that stays stuck until it
//! is cleared (`super::virtual_nxp`).

use embedded_hal_async::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};

use crate::input::sensor::Fault;

/// Why a TWI transfer failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TwiError {
    /// No ACK to the address.
    AddressNack,
    /// No ACK to a data byte.
    DataNack,
    /// A received byte was overwritten.
    Overrun,
    /// No event before the transfer's deadline (a stuck bus).
    Timeout,
}

impl TwiError {
    /// The supervisor's name for it: a timeout is a stuck bus, the rest
    /// are bus errors.
    pub const fn fault(self) -> Fault {
        match self {
            TwiError::Timeout => Fault::Timeout,
            _ => Fault::Bus,
        }
    }
}

impl embedded_hal_async::i2c::Error for TwiError {
    fn kind(&self) -> ErrorKind {
        match self {
            TwiError::AddressNack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
            TwiError::DataNack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Data),
            TwiError::Overrun => ErrorKind::Overrun,
            TwiError::Timeout => ErrorKind::Other,
        }
    }
}

#[cfg(feature = "lsm303agr")]
impl crate::input::lsm303::BusFault for TwiError {
    fn fault(&self) -> Fault {
        TwiError::fault(*self)
    }
}

/// A bus that can free a slave holding SDA low: nine SCL clocks with SDA
/// released, then a STOP.
pub trait BusClear {
    /// Clears the bus (and leaves the controller ready for a transfer).
    fn clear_bus(&mut self);
}

/// A bus whose owner can keep it idle for a while: the wait an NXP chip
/// needs after its soft reset before it answers again
/// ([`crate::board::microbit_v1::nxp_driver::configure`]). The firmware
/// busy-waits (its TWI driver is blocking); the virtual bus moves its clock.
pub trait Pause {
    /// Holds the bus idle for `us` µs.
    fn pause_us(&mut self, us: u32);
}

/// A bus that is cleared before its first transfer and after every failed
/// one (see the module doc).
#[derive(Debug)]
pub struct Recovering<B> {
    bus: B,
    cleared: bool,
    clears: u32,
}

impl<B: BusClear> Recovering<B> {
    /// Wraps `bus`; the first transfer clears it first.
    pub const fn new(bus: B) -> Self {
        Self {
            bus,
            cleared: false,
            clears: 0,
        }
    }

    /// Bus clears so far.
    pub const fn clears(&self) -> u32 {
        self.clears
    }

    /// The bus.
    pub fn bus(&mut self) -> &mut B {
        &mut self.bus
    }

    fn clear(&mut self) {
        self.bus.clear_bus();
        self.clears = self.clears.wrapping_add(1);
        self.cleared = true;
    }
}

impl<B: ErrorType> ErrorType for Recovering<B> {
    type Error = B::Error;
}

impl<B: I2c + BusClear> I2c for Recovering<B> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        if !self.cleared {
            self.clear();
        }
        let result = self.bus.transaction(address, operations).await;
        if result.is_err() {
            self.clear();
        }
        result
    }
}

impl<B: Pause> Pause for Recovering<B> {
    fn pause_us(&mut self, us: u32) {
        self.bus.pause_us(us);
    }
}
