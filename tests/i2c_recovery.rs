//! The boards' bus-clear rule (`board::i2c::Recovering`): a clear before the
//! first transfer and after each one that failed on the wire, and none after
//! a transfer the driver refused before any traffic. Every board's sensor bus
//! runs under it; this runs it on a scripted bus.

use embassy_futures::block_on;
use embedded_hal_async::i2c::{ErrorKind, ErrorType, I2c, Operation};
use marble_rolling::board::i2c::{ClearBus, Recovering};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Failure {
    /// Refused by the driver: nothing reached the bus.
    Refused,
    /// No ACK on the wire.
    Nack,
}

impl embedded_hal_async::i2c::Error for Failure {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// A bus that answers each transfer with the next outcome of its script and
/// logs every transfer and clear in order.
struct Scripted {
    outcomes: Vec<Result<(), Failure>>,
    log: Vec<&'static str>,
}

impl ErrorType for Scripted {
    type Error = Failure;
}

impl I2c for Scripted {
    async fn transaction(
        &mut self,
        _address: u8,
        _operations: &mut [Operation<'_>],
    ) -> Result<(), Failure> {
        self.log.push("transfer");
        self.outcomes.remove(0)
    }
}

impl ClearBus for Scripted {
    fn clear_bus(&mut self) {
        self.log.push("clear");
    }

    fn on_the_wire(error: &Failure) -> bool {
        *error == Failure::Nack
    }
}

/// Like [`Scripted`], with the trait's default: every failure may have
/// reached the wire.
struct Blunt(Scripted);

impl ErrorType for Blunt {
    type Error = Failure;
}

impl I2c for Blunt {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Failure> {
        self.0.transaction(address, operations).await
    }
}

impl ClearBus for Blunt {
    fn clear_bus(&mut self) {
        self.0.clear_bus();
    }
}

fn read(bus: &mut impl I2c<Error = Failure>) -> Result<(), Failure> {
    let mut byte = [0u8; 1];
    block_on(bus.write_read(0x19, &[0x0F], &mut byte))
}

#[test]
fn clears_first_and_after_a_failure_on_the_wire_only() {
    let mut bus = Recovering::new(Scripted {
        outcomes: vec![Ok(()), Err(Failure::Refused), Err(Failure::Nack), Ok(())],
        log: Vec::new(),
    });
    assert_eq!(read(&mut bus), Ok(()));
    assert_eq!(read(&mut bus), Err(Failure::Refused));
    assert_eq!(read(&mut bus), Err(Failure::Nack));
    assert_eq!(read(&mut bus), Ok(()));
    assert_eq!(bus.clears(), 2);
    assert_eq!(
        bus.bus().log,
        ["clear", "transfer", "transfer", "transfer", "clear", "transfer"]
    );
}

#[test]
fn a_bus_that_cannot_tell_clears_after_every_failure() {
    let mut bus = Recovering::new(Blunt(Scripted {
        outcomes: vec![Err(Failure::Refused), Ok(())],
        log: Vec::new(),
    }));
    assert_eq!(read(&mut bus), Err(Failure::Refused));
    assert_eq!(read(&mut bus), Ok(()));
    assert_eq!(bus.clears(), 2);
    assert_eq!(bus.bus().0.log, ["clear", "transfer", "clear", "transfer"]);
}
