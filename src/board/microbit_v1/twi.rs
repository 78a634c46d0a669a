//! The v1's I²C bus as the sensor stack sees it: the TWI driver's errors
//! ([`TwiError`], what the supervisor makes of them) and the pause an NXP
//! chip needs ([`Pause`]). The bus clears through the boards' shared rule,
//! [`Recovering`], after every failed transfer: the TWI has no error that
//! stays off the wire. The host tests run it against a virtual bus that
//! stays stuck until it is cleared (`super::virtual_twi`).

use embedded_hal_async::i2c::{ErrorKind, NoAcknowledgeSource};

use crate::board::i2c::{ClearBus, Recovering};
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

/// A bus whose owner can keep it idle for a while: the wait an NXP chip
/// needs after its soft reset before it answers again
/// ([`crate::board::microbit_v1::nxp_driver::configure`]). The firmware
/// busy-waits (its TWI driver is blocking); the virtual bus moves its clock.
pub trait Pause {
    /// Holds the bus idle for `us` µs.
    fn pause_us(&mut self, us: u32);
}

impl<B: Pause + ClearBus> Pause for Recovering<B> {
    fn pause_us(&mut self, us: u32) {
        self.bus().pause_us(us);
    }
}
