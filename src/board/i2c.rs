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

// The bus clear itself (UM10204 §3.1.16), on a board's lines as GPIOs.

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
