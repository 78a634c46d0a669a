//! The v1's TWI with one virtual accelerometer on it ([`VirtualTwi`]): an
//! MMA8653FC or FXOS8700CQ ([`VirtualNxp`]), or the LSM303AGR a v1.5 may carry
//! ([`VirtualChip`]), faults and tilt from the shared [`ChipControl`].

use embedded_hal_async::i2c::{ErrorType, I2c, Operation};

use super::accel::Accelerometer;
use super::twi::{Pause, TwiError};
use super::virtual_nxp::VirtualNxp;
use crate::board::i2c::ClearBus;
use crate::board::virtual_lsm303agr::{
    ChipControl, InjectedFault, SampleSource, VirtualLsm303agr, MICROBIT_V2,
};
use crate::input::axes::AccelMg;

/// The accelerometer a virtual v1 board carries.
#[derive(Clone, Debug)]
pub enum VirtualChip {
    /// An MMA8653FC (v1.3, v1.3B) or an FXOS8700CQ (v1.5).
    Nxp(VirtualNxp),
    /// The LSM303AGR of a v1.5: accelerometer at 0x19, magnetometer at
    /// 0x1E, the FXOS8700CQ's address; mounted as on the v2 (the DAL's and
    /// CODAL's LSM303 tables agree, `super::accel::LSM303AGR_AXIS_MAP`).
    Lsm303agr(VirtualLsm303agr),
}

impl VirtualChip {
    /// `chip` at power-on, as a v1 board carries it.
    pub const fn new(chip: Accelerometer) -> Self {
        match chip {
            Accelerometer::Lsm303agr => {
                VirtualChip::Lsm303agr(VirtualLsm303agr::placed(MICROBIT_V2))
            }
            nxp => VirtualChip::Nxp(VirtualNxp::new(nxp)),
        }
    }

    /// Which chip it is.
    pub const fn kind(&self) -> Accelerometer {
        match self {
            VirtualChip::Nxp(chip) => chip.chip,
            VirtualChip::Lsm303agr(_) => Accelerometer::Lsm303agr,
        }
    }

    /// Whether a transfer to `address` is acknowledged.
    pub fn acknowledges(&self, address: u8) -> bool {
        match self {
            VirtualChip::Nxp(chip) => address == chip.address() && !chip.resetting(),
            VirtualChip::Lsm303agr(chip) => chip.acknowledges(address),
        }
    }

    fn power_on_reset(&mut self) {
        match self {
            VirtualChip::Nxp(chip) => chip.power_on_reset(),
            VirtualChip::Lsm303agr(chip) => chip.power_on_reset(),
        }
    }

    fn feed(&mut self, tilt: AccelMg, fault: InjectedFault, now_us: u64) {
        let (frozen, garbage) = (
            fault == InjectedFault::FrozenData,
            fault == InjectedFault::Garbage,
        );
        match self {
            VirtualChip::Nxp(chip) => {
                chip.set_tilt(tilt);
                chip.set_faults(frozen, garbage);
                chip.advance_to(now_us);
            }
            VirtualChip::Lsm303agr(chip) => {
                chip.set_tilt(tilt);
                chip.set_source(if frozen {
                    SampleSource::Frozen
                } else if garbage {
                    SampleSource::Garbage
                } else {
                    SampleSource::Tilt
                });
                chip.advance_to(now_us);
            }
        }
    }

    /// `false` when a data byte was not acknowledged.
    fn write(&mut self, address: u8, bytes: &[u8]) -> bool {
        match self {
            VirtualChip::Nxp(chip) => chip.i2c_write(bytes),
            VirtualChip::Lsm303agr(chip) => {
                chip.i2c_write(address, bytes);
                true
            }
        }
    }

    fn read(&mut self, address: u8, buffer: &mut [u8]) {
        match self {
            VirtualChip::Nxp(chip) => chip.i2c_read(buffer),
            VirtualChip::Lsm303agr(chip) => chip.i2c_read(address, buffer),
        }
    }
}

impl From<VirtualNxp> for VirtualChip {
    fn from(chip: VirtualNxp) -> Self {
        VirtualChip::Nxp(chip)
    }
}

impl From<VirtualLsm303agr> for VirtualChip {
    fn from(chip: VirtualLsm303agr) -> Self {
        VirtualChip::Lsm303agr(chip)
    }
}

/// The v1's TWI with one virtual accelerometer on it, faults from `control`,
/// time from `now_us` (µs): what the v1's blocking driver would return, as
/// the async trait the sensor stack takes (every transfer completes at once).
pub struct VirtualTwi<'a, C: Fn() -> u64> {
    chip: VirtualChip,
    control: &'a ChipControl,
    now_us: C,
    stuck: bool,
    resets_seen: u32,
    transfers: u32,
    clears: u32,
    /// Bit per 7-bit address a transfer was started to.
    addressed: u128,
    /// Time spent in [`Pause::pause_us`], µs: added to `now_us`, as the
    /// firmware's clock runs on while it waits.
    paused_us: u64,
}

impl<'a, C: Fn() -> u64> VirtualTwi<'a, C> {
    /// `chip` on the bus.
    pub fn new(chip: impl Into<VirtualChip>, control: &'a ChipControl, now_us: C) -> Self {
        Self {
            chip: chip.into(),
            control,
            now_us,
            stuck: false,
            resets_seen: control.reset_requests(),
            transfers: 0,
            clears: 0,
            addressed: 0,
            paused_us: 0,
        }
    }

    /// The chip (inspection).
    pub fn chip(&self) -> &VirtualChip {
        &self.chip
    }

    /// The chip, if it is an NXP one (inspection).
    pub fn nxp(&self) -> Option<&VirtualNxp> {
        match &self.chip {
            VirtualChip::Nxp(chip) => Some(chip),
            VirtualChip::Lsm303agr(_) => None,
        }
    }

    /// Whether the bus is held stuck.
    pub const fn stuck(&self) -> bool {
        self.stuck
    }

    /// Transfers attempted.
    pub const fn transfers(&self) -> u32 {
        self.transfers
    }

    /// Bus clears received.
    pub const fn clears(&self) -> u32 {
        self.clears
    }

    /// Whether any transfer was started to `address` (7-bit), answered or
    /// not.
    pub const fn addressed(&self, address: u8) -> bool {
        address < 128 && self.addressed & (1 << address) != 0
    }

    fn apply(&mut self, address: u8) -> Result<(), TwiError> {
        self.transfers = self.transfers.wrapping_add(1);
        self.addressed |= 1u128 << (address & 0x7F);
        let fault = self.control.fault();
        let requests = self.control.reset_requests();
        if requests != self.resets_seen {
            self.resets_seen = requests;
            self.chip.power_on_reset();
        }
        self.chip
            .feed(self.control.tilt(), fault, (self.now_us)() + self.paused_us);
        if fault == InjectedFault::StuckBus {
            self.stuck = true;
        }
        if self.stuck {
            return Err(TwiError::Timeout);
        }
        if fault == InjectedFault::Nak {
            return Err(TwiError::AddressNack);
        }
        Ok(())
    }
}

impl<C: Fn() -> u64> ErrorType for VirtualTwi<'_, C> {
    type Error = TwiError;
}

impl<C: Fn() -> u64> I2c for VirtualTwi<'_, C> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), TwiError> {
        self.apply(address)?;
        if !self.chip.acknowledges(address) {
            return Err(TwiError::AddressNack);
        }
        for operation in operations.iter_mut() {
            match operation {
                Operation::Write(bytes) => {
                    if !self.chip.write(address, bytes) {
                        return Err(TwiError::DataNack);
                    }
                }
                Operation::Read(buffer) => self.chip.read(address, buffer),
            }
        }
        Ok(())
    }
}

impl<C: Fn() -> u64> ClearBus for VirtualTwi<'_, C> {
    /// Frees the bus, unless the slave is still faulty.
    fn clear_bus(&mut self) {
        self.clears = self.clears.wrapping_add(1);
        if self.control.fault() != InjectedFault::StuckBus {
            self.stuck = false;
        }
    }
}

impl<C: Fn() -> u64> Pause for VirtualTwi<'_, C> {
    fn pause_us(&mut self, us: u32) {
        self.paused_us += u64::from(us);
    }
}
