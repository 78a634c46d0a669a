//! What every board's I²C bus to its accelerometer shares: the rule that
//! clears the bus. A reset in the middle of a read (a reflash, a brown-out)
//! can leave the accelerometer holding SDA low, waiting for clocks that never
//! come; nine clocks and a STOP free it (the I²C specification's bus clear,
//! UM10204 §3.1.16). So each board's bus is cleared before its first
//! transfer and after every transfer that failed on the wire
//! ([`Recovering`]); how a board clears its lines, and which of its errors
//! reached the wire, is the board's ([`ClearBus`]). Pure logic, so the host
//! tests run the rule against virtual buses that stay stuck until cleared.

use embedded_hal_async::i2c::{ErrorType, I2c, Operation};

/// A bus that can free a slave holding SDA low: nine SCL clocks with SDA
/// released, then a STOP.
pub trait ClearBus: ErrorType {
    /// Clears the bus (and leaves the controller ready for a transfer).
    fn clear_bus(&mut self);

    /// Whether a transfer that failed with `error` may have left the bus
    /// stuck: it reached the wire. A transfer the driver refused before any
    /// traffic (a buffer too long) leaves the bus as it was. Every error, if
    /// the board cannot tell.
    fn on_the_wire(error: &Self::Error) -> bool {
        let _ = error;
        true
    }
}

/// A bus that is cleared before its first transfer and after every one that
/// failed on the wire (see the module doc).
#[derive(Debug)]
pub struct Recovering<B> {
    bus: B,
    cleared: bool,
    clears: u32,
}

impl<B: ClearBus> Recovering<B> {
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

impl<B: I2c + ClearBus> I2c for Recovering<B> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        if !self.cleared {
            self.clear();
        }
        let result = self.bus.transaction(address, operations).await;
        if let Err(error) = &result {
            if B::on_the_wire(error) {
                self.clear();
            }
        }
        result
    }
}
