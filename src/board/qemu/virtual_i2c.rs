//! A virtual I²C bus with the [`VirtualLsm303agr`] on it, behaving like
//! embassy-nrf 0.11's `Twim` (the micro:bit's bus): an
//! [`embedded_hal_async::i2c::I2c`] the `lsm303agr` driver runs on unchanged.
//!
//! # The DMA rule
//!
//! The nRF's TWIM moves bytes by EasyDMA, which reaches RAM only. embassy-nrf's
//! `Twim::set_tx_buffer` therefore checks every write buffer: one in RAM is
//! used as it is; one elsewhere (a constant the compiler put in flash) is
//! copied into the `tx_ram_buffer` given to `Twim::new`, and refused with
//! `Error::RAMBufferTooSmall` — before anything reaches the bus — when that
//! buffer is shorter than the write. The `lsm303agr` driver reads a register
//! with `write_read(address, &[REGISTER], ..)`: a promoted constant, in
//! flash. Without a copy buffer every read fails. [`VirtualTwim`] applies the same rule with the same test (embassy's
//! `slice_in_ram`: an empty slice passes, else `start >= RAM start` and
//! `start + len < RAM end`) against a [`Ram`]: [`RamRange`] on a target
//! ([`QEMU_RAM`](super::QEMU_RAM) on QEMU), a predicate on the host.
//!
//! # Transactions
//!
//! As embassy's `Twim::transaction`, the operations are run in the chunks the
//! TWIM can do in one go — write then read (repeated start), read then write,
//! a lone read, a write — each chunk's buffers checked before it starts. Two
//! reads in a row, which embassy refuses with a panic, are refused here with
//! [`TwimError::Unsupported`].
//!
//! # Faults
//!
//! From the [`ChipControl`] at the start of each chunk that passed the
//! checks: [`InjectedFault::Nak`] fails it with [`TwimError::AddressNack`]
//! (as does any address but the chip's two), no register changes;
//! [`InjectedFault::StuckBus`] never completes it (the future stays pending:
//! the caller's timeout must end it; dropping it is safe, nothing was
//! applied) and leaves the bus stuck, as a slave holding SDA low leaves a
//! real one: every later transfer hangs too, the fault lifted or not, until
//! the firmware runs its bus clear ([`VirtualTwim::clear_bus`], the shared
//! [`clear_bus`] on the virtual lines: nine clocks free the slave once the
//! fault is lifted, none while it is in force) or the chip is reset (a
//! brown-out resets its I²C state machine too); frozen data, garbage and a
//! chip reset are the chip's
//! ([`VirtualLsm303agr`]). Time comes from the caller's clock (`now_us`),
//! read once per chunk, so host tests step it by hand and the firmware passes
//! embassy-time's.

use embedded_hal_async::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};

use crate::board::i2c::{clear_bus, BusClear, BusLines};
use crate::board::virtual_lsm303agr::{ChipControl, InjectedFault, SampleSource, VirtualLsm303agr};

/// The largest transfer the TWIM's EasyDMA takes (nRF52833, embassy-nrf's
/// `EASY_DMA_SIZE`).
pub(crate) const EASY_DMA_SIZE: usize = (1 << 16) - 1;

/// Why a transfer failed: embassy-nrf's `twim::Error` variants that can occur
/// here, plus [`TwimError::Unsupported`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TwimError {
    /// A write buffer over `EASY_DMA_SIZE`.
    TxBufferTooLong,
    /// A read buffer over `EASY_DMA_SIZE`.
    RxBufferTooLong,
    /// A write buffer not in RAM and longer than the copy buffer: refused
    /// before anything reached the bus.
    RAMBufferTooSmall,
    /// The address was not acknowledged.
    AddressNack,
    /// Two reads in a row (embassy-nrf panics on it).
    Unsupported,
}

impl embedded_hal_async::i2c::Error for TwimError {
    fn kind(&self) -> ErrorKind {
        match self {
            TwimError::AddressNack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address),
            _ => ErrorKind::Other,
        }
    }
}

/// Where the TWIM's DMA can read: which buffers are in RAM.
pub trait Ram {
    /// Whether the `len` bytes at address `start` are all in RAM.
    fn holds(&self, start: usize, len: usize) -> bool;
}

/// RAM as one address range `start..end`, tested as embassy-nrf's
/// `slice_in_ram` does (an empty slice passes; the end is exclusive and a
/// slice ending exactly at it is refused, as there).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RamRange {
    /// First RAM address.
    pub start: usize,
    /// One past the last RAM address.
    pub end: usize,
}

impl Ram for RamRange {
    fn holds(&self, start: usize, len: usize) -> bool {
        len == 0 || (start >= self.start && start.saturating_add(len) < self.end)
    }
}

impl<F: Fn(usize, usize) -> bool> Ram for F {
    fn holds(&self, start: usize, len: usize) -> bool {
        self(start, len)
    }
}

/// The virtual bus (see the module doc): the chip, the copy buffer for write
/// buffers outside RAM (embassy-nrf's `tx_ram_buffer`; empty: none), the
/// shared [`ChipControl`], a clock `now_us` (µs) and the [`Ram`] test.
pub struct VirtualTwim<'a, C, R> {
    chip: VirtualLsm303agr,
    control: &'a ChipControl,
    copy_buffer: &'a mut [u8],
    now_us: C,
    ram: R,
    resets_seen: u32,
    last_error: Option<TwimError>,
    /// A transfer hung with the slave holding SDA low; only a bus clear or
    /// a chip reset frees it.
    stuck: bool,
    clears: u32,
}

impl<'a, C: FnMut() -> u64, R: Ram> VirtualTwim<'a, C, R> {
    /// A bus with `chip` on it.
    pub fn new(
        chip: VirtualLsm303agr,
        control: &'a ChipControl,
        copy_buffer: &'a mut [u8],
        now_us: C,
        ram: R,
    ) -> Self {
        Self {
            chip,
            resets_seen: control.reset_requests(),
            control,
            copy_buffer,
            now_us,
            ram,
            last_error: None,
            stuck: false,
            clears: 0,
        }
    }

    /// Whether the bus is held stuck (see the module doc).
    pub fn stuck(&self) -> bool {
        self.stuck
    }

    /// Bus clears run so far.
    pub fn clears(&self) -> u32 {
        self.clears
    }

    /// The I²C bus clear on the bus lines (the shared [`clear_bus`]): frees a
    /// stuck bus unless the stuck-bus fault is still in force.
    pub fn clear_bus(&mut self) -> BusClear {
        let mut lines = Lines {
            scl: true,
            sda: true,
            holding: self.stuck,
            wedged: self.control.fault() == InjectedFault::StuckBus,
            bits_left: HELD_BITS,
        };
        let outcome = clear_bus(&mut lines);
        self.clears = self.clears.wrapping_add(1);
        if outcome.is_clear() {
            self.stuck = false;
        }
        outcome
    }

    /// The chip (inspection).
    pub fn chip(&self) -> &VirtualLsm303agr {
        &self.chip
    }

    /// The chip, mutably (tests).
    pub fn chip_mut(&mut self) -> &mut VirtualLsm303agr {
        &mut self.chip
    }

    /// The control it applies.
    pub fn control(&self) -> &'a ChipControl {
        self.control
    }

    /// The copy buffer's length.
    pub fn copy_buffer_len(&self) -> usize {
        self.copy_buffer.len()
    }

    /// The last error a transfer ended with (`None` before any).
    pub fn last_error(&self) -> Option<TwimError> {
        self.last_error
    }

    /// embassy-nrf's `set_tx_buffer` check: `Ok(true)` when `buffer` must go
    /// through the copy buffer, `Ok(false)` when it is in RAM.
    fn check_tx(&self, buffer: &[u8]) -> Result<bool, TwimError> {
        let copy = !self.ram.holds(buffer.as_ptr() as usize, buffer.len());
        if copy && buffer.len() > self.copy_buffer.len() {
            return Err(TwimError::RAMBufferTooSmall);
        }
        if buffer.len() > EASY_DMA_SIZE {
            return Err(TwimError::TxBufferTooLong);
        }
        Ok(copy)
    }

    fn check_rx(buffer: &[u8]) -> Result<(), TwimError> {
        if buffer.len() > EASY_DMA_SIZE {
            return Err(TwimError::RxBufferTooLong);
        }
        Ok(())
    }

    /// How many operations the TWIM runs in one go from the start of `ops`
    /// (embassy-nrf's `setup_operations`), checking their buffers; for the
    /// write among them, whether it goes through the copy buffer.
    fn setup(&self, ops: &[Operation<'_>]) -> Result<(usize, bool), TwimError> {
        match ops {
            [Operation::Read(_), Operation::Read(_), ..] => Err(TwimError::Unsupported),
            [Operation::Read(rd), Operation::Write(wr), ..] => {
                let copy = self.check_tx(wr)?;
                Self::check_rx(rd)?;
                Ok((2, copy))
            }
            [Operation::Read(rd)] => {
                Self::check_rx(rd)?;
                Ok((1, false))
            }
            [Operation::Write(wr), Operation::Read(rd)] if !wr.is_empty() && !rd.is_empty() => {
                let copy = self.check_tx(wr)?;
                Self::check_rx(rd)?;
                Ok((2, copy))
            }
            [Operation::Write(wr), ..] => Ok((1, self.check_tx(wr)?)),
            [] => Ok((0, false)),
        }
    }

    /// Brings the chip up to date with the control and the clock.
    fn sync(&mut self) {
        let requests = self.control.reset_requests();
        if requests != self.resets_seen {
            self.resets_seen = requests;
            self.chip.power_on_reset();
            self.control.count_reset();
        }
        self.chip.set_tilt(self.control.tilt());
        self.chip.set_source(match self.control.fault() {
            InjectedFault::FrozenData => SampleSource::Frozen,
            InjectedFault::Garbage => SampleSource::Garbage,
            _ => SampleSource::Tilt,
        });
        let now = (self.now_us)();
        self.chip.advance_to(now);
    }

    /// Runs one chunk (already checked) on the bus.
    async fn run(
        &mut self,
        address: u8,
        ops: &mut [Operation<'_>],
        copy: bool,
    ) -> Result<(), TwimError> {
        self.control.count_transfer();
        if self.control.reset_requests() != self.resets_seen {
            self.stuck = false;
        }
        if self.control.fault() == InjectedFault::StuckBus {
            self.stuck = true;
        }
        if self.stuck {
            core::future::pending::<()>().await;
        }
        self.sync();
        if self.control.fault() == InjectedFault::Nak || !self.chip.acknowledges(address) {
            return Err(TwimError::AddressNack);
        }
        for op in ops.iter_mut() {
            match op {
                Operation::Write(bytes) if copy => {
                    // What the DMA sends is the copy in RAM.
                    let len = bytes.len();
                    let Some(ram) = self.copy_buffer.get_mut(..len) else {
                        return Err(TwimError::RAMBufferTooSmall);
                    };
                    ram.copy_from_slice(bytes);
                    self.chip.i2c_write(address, ram);
                }
                Operation::Write(bytes) => self.chip.i2c_write(address, bytes),
                Operation::Read(buffer) => self.chip.i2c_read(address, buffer),
            }
        }
        Ok(())
    }

    async fn transfer(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), TwimError> {
        let mut rest = operations;
        while !rest.is_empty() {
            let (count, copy) = match self.setup(rest) {
                Ok(setup) => setup,
                Err(e) => {
                    self.control.count_refused();
                    return Err(e);
                }
            };
            let (chunk, tail) = rest.split_at_mut(count.clamp(1, rest.len()));
            self.run(address, chunk, copy).await?;
            rest = tail;
        }
        Ok(())
    }
}

/// Bits a stuck slave still has to shift out once it may let go: a slave
/// transmitter stopped after the first bits of a `0x0X` byte holds SDA low
/// for the rest of it.
const HELD_BITS: u8 = 5;

/// The two lines during a bus clear, the slave's side modelled: while it
/// holds SDA, each SCL pulse shifts out one more bit; a wedged slave (the
/// fault still in force) never lets go. Nobody stretches the clock.
struct Lines {
    scl: bool,
    sda: bool,
    holding: bool,
    wedged: bool,
    bits_left: u8,
}

impl BusLines for Lines {
    fn set_scl(&mut self, high: bool) {
        if high && !self.scl && self.holding && !self.wedged {
            self.bits_left = self.bits_left.saturating_sub(1);
            if self.bits_left == 0 {
                self.holding = false;
            }
        }
        self.scl = high;
    }

    fn set_sda(&mut self, high: bool) {
        self.sda = high;
    }

    fn scl(&mut self) -> bool {
        self.scl
    }

    fn sda(&mut self) -> bool {
        self.sda && !self.holding
    }

    fn half_period(&mut self) {}
}

impl<C, R> ErrorType for VirtualTwim<'_, C, R> {
    type Error = TwimError;
}

impl<C: FnMut() -> u64, R: Ram> I2c for VirtualTwim<'_, C, R> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), Self::Error> {
        let result = self.transfer(address, operations).await;
        if let Err(e) = result {
            self.last_error = Some(e);
        }
        result
    }
}
