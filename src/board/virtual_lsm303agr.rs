//! A virtual LSM303AGR: the accelerometer's registers as the `lsm303agr`
//! driver (1.1) uses them, serving a tilt that a keyboard or a script sets,
//! and the faults a real chip on a real bus shows, injected at run time.
//!
//! The QEMU board has no accelerometer, so without this its input stack
//! (driver, [`TiltPipeline`](crate::input::sensor::TiltPipeline) supervision)
//! would run nowhere but on a micro:bit. The chip sits on a virtual I²C bus,
//! [`VirtualTwim`](crate::board::qemu::virtual_i2c::VirtualTwim), which adds the bus
//! behaviour (address acknowledge, a stuck bus, the nRF TWIM's DMA rule).
//!
//! # What is modelled
//!
//! * Accelerometer (I²C address [`ACCEL_ADDRESS`]): `WHO_AM_I_A` (0x33),
//!   `TEMP_CFG_REG_A`, `CTRL_REG1_A`..`CTRL_REG6_A`, `REFERENCE_A`,
//!   `FIFO_CTRL_REG_A`, the interrupt and click configuration registers
//!   (stored, without effect), `STATUS_REG_A` and `OUT_X_L_A`..`OUT_Z_H_A`.
//!   The register pointer auto-increments when bit 7 of the sub-address is
//!   set, else every byte of a burst is the same register (datasheet §6.1.1).
//! * Output data rate from `CTRL_REG1_A` (ODR bits and `LPen`; 1 Hz to
//!   5.376 kHz): the n-th sample is taken `n / ODR` after the rate was set,
//!   on the caller's clock (`VirtualLsm303agr::advance_to`). A new sample
//!   sets `XDA`/`YDA`/`ZDA` and `ZYXDA`; reading an axis's high byte clears
//!   its bit (and `ZYXDA`); a sample that overwrites an unread one sets the
//!   overrun bits.
//! * Resolution from `LPen` and `HR` (low-power 8-bit, normal 10-bit,
//!   high-resolution 12-bit, left-justified in 16 bits; `HR` wins over `LPen`
//!   as in the driver's `get_accel_mode`), full scale ±2/4/8/16 g from `FS`,
//!   `BLE` (byte order) and `BDU` (block data update: while only one byte of
//!   an axis has been read, no new sample is latched).
//! * Sensitivity: the mg per LSB the driver converts back with
//!   (high resolution `FS/2`, normal `2·FS`, low power `8·FS`; `FS` in g), so
//!   the driver reads the set tilt back within one LSB. (The datasheet's ±16 g
//!   sensitivities are 12/48/192 mg per LSB, not the driver's 8/32/128: at
//!   that range a real chip reads 1.5× what the driver reports. The toy runs
//!   at ±2 g, where both agree.)
//! * The tilt: a board-frame reading in milli-g, turned into the chip's raw
//!   axes by the chip's own [`Placement`] on the board (where each of its
//!   axes points: [`MICROBIT_V2`]), then quantised (rounded to the nearest
//!   LSB, saturated at full scale). The firmware turns raw axes back with its
//!   own table, `board::accel_link::AXIS_MAP`; the two are written apart, so a
//!   sign or axis wrong in either reads a wrong tilt in the tests and in QEMU.
//! * Power-on values: `CTRL_REG1_A` = 0x07 (power-down, axes enabled), the
//!   other control registers 0, no data ready; `VirtualLsm303agr::power_on_reset`
//!   brings them back (the injected chip reset).
//! * Magnetometer (I²C address [`MAG_ADDRESS`]): only enough for the driver's
//!   `init()` (it writes `CFG_REG_C_M`): `WHO_AM_I_M` (0x40), the
//!   configuration registers stored; its outputs read 0. The addresses below
//!   0x40, which the datasheet's register map (table 21) leaves reserved,
//!   read a byte the test chooses ([`VirtualLsm303agr::set_reserved_mag_read`],
//!   0 by default): what a real chip answers there is not documented.
//!
//! * Boot after power-up: none by default; a test may have the chip answer
//!   nothing until a time of its choosing
//!   ([`VirtualLsm303agr::set_ready_at_us`]).
//!
//! Not modelled: the temperature sensor (reads 0), the FIFO, interrupts and
//! click detection, self-test, the axis-enable bits (every axis converts),
//! the turn-on and settling time after a mode change (the first sample is
//! valid), noise.
//!
//! # Faults ([`InjectedFault`])
//!
//! Set on a [`ChipControl`] shared by whoever injects them (keys, a script, a
//! test) and the bus that applies them: no acknowledge, a stuck bus, frozen
//! data (conversions stall: the output registers keep their values and no new
//! data is flagged, a re-init does not help), garbage (random samples within
//! the top tenth of the full scale on every axis, so every one is implausible:
//! over 3 g in total at any range) and a chip reset (registers back to their
//! power-on values: the driver must initialise the chip again).

mod control;
mod placement;
mod registers;

pub use control::{ChipControl, InjectedFault};
pub use placement::{to_sensor_frame, Placement, MICROBIT_V2};
pub use registers::*;

use crate::input::axes::AccelMg;
use crate::input::sensor::AxisMap;

/// Where new samples come from.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum SampleSource {
    /// The set tilt.
    Tilt,
    /// None: conversions stall ([`InjectedFault::FrozenData`]).
    Frozen,
    /// Random implausible values ([`InjectedFault::Garbage`]).
    Garbage,
}

/// First magnetometer register modelled.
const MAG_FIRST: u8 = 0x40;
/// Magnetometer registers modelled (0x40..0x70).
const MAG_COUNT: usize = 0x30;

/// The virtual chip: registers, sampling clock, output latch. Transfers come
/// from its bus ([`VirtualTwim`](crate::board::qemu::virtual_i2c::VirtualTwim)), which
/// also feeds it the time (`VirtualLsm303agr::advance_to`), the tilt and
/// the sample source; host tests can drive it directly too.
#[derive(Clone, Debug)]
pub struct VirtualLsm303agr {
    placement: Placement,
    accel: [u8; 0x40],
    mag: [u8; MAG_COUNT],
    /// Register pointers (sub-address, with the auto-increment bit for the
    /// accelerometer).
    accel_pointer: u8,
    mag_pointer: u8,
    /// Time of the last [`VirtualLsm303agr::advance_to`], µs.
    now_us: u64,
    /// When the output data rate was last set, µs.
    epoch_us: u64,
    /// Sample instants since `epoch_us` already taken (or skipped).
    samples: u64,
    /// When the next sample is due, µs.
    next_due_us: u64,
    /// Per axis: bit 0 low byte, bit 1 high byte read since the last sample
    /// (block data update holds the output while only one was).
    half_read: [u8; 3],
    tilt: AccelMg,
    source: SampleSource,
    rng: u32,
    /// Samples latched since power-on (diagnostics).
    latched: u32,
    /// What the magnetometer's reserved addresses below 0x40 read.
    reserved_mag_read: u8,
    /// Until this time on its clock the chip is still booting and
    /// acknowledges nothing.
    ready_at_us: u64,
}

impl VirtualLsm303agr {
    /// A chip at power-on, placed as the board's firmware table `map`
    /// assumes ([`Placement::assumed_by`]): a sign error in `map` cannot
    /// show. Prefer [`VirtualLsm303agr::placed`].
    pub const fn new(map: AxisMap) -> Self {
        Self::placed(Placement::assumed_by(&map))
    }

    /// A chip at power-on, mounted on its board as `placement` says (the
    /// tilt set later is in the board frame).
    pub const fn placed(placement: Placement) -> Self {
        let mut chip = Self {
            placement,
            accel: [0; 0x40],
            mag: [0; MAG_COUNT],
            accel_pointer: 0,
            mag_pointer: 0,
            now_us: 0,
            epoch_us: 0,
            samples: 0,
            next_due_us: 0,
            half_read: [0; 3],
            tilt: AccelMg::LEVEL,
            source: SampleSource::Tilt,
            rng: 0x2545_f491,
            latched: 0,
            reserved_mag_read: 0,
            ready_at_us: 0,
        };
        chip.accel[reg::CTRL_REG1_A as usize] = CTRL_REG1_A_RESET;
        chip.mag[(reg::CFG_REG_A_M - MAG_FIRST) as usize] = CFG_REG_A_M_RESET;
        chip
    }

    /// Back to the power-on state (registers, outputs, flags, pointers); the
    /// clock, the tilt and the sample source are kept.
    pub(crate) fn power_on_reset(&mut self) {
        let fresh = Self::placed(self.placement);
        self.accel = fresh.accel;
        self.mag = fresh.mag;
        self.accel_pointer = 0;
        self.mag_pointer = 0;
        self.samples = 0;
        self.epoch_us = self.now_us;
        self.next_due_us = self.now_us;
        self.half_read = [0; 3];
    }

    /// Sets the tilt (a board-frame reading) the next samples take.
    pub(crate) fn set_tilt(&mut self, tilt: AccelMg) {
        self.tilt = tilt;
    }

    /// Sets where the next samples come from.
    pub(crate) fn set_source(&mut self, source: SampleSource) {
        self.source = source;
    }

    /// Sets what a read of a reserved magnetometer address below 0x40
    /// returns (the datasheet does not say; kept across a chip reset).
    pub fn set_reserved_mag_read(&mut self, value: u8) {
        self.reserved_mag_read = value;
    }

    /// Samples latched since power-on.
    pub fn latched(&self) -> u32 {
        self.latched
    }

    /// The output data rate in force, Hz (0: powered down or an invalid
    /// combination).
    pub fn odr_hz(&self) -> u32 {
        let ctrl1 = self.accel[reg::CTRL_REG1_A as usize];
        let low_power = ctrl1 & CTRL1_LPEN != 0;
        match ctrl1 >> 4 {
            1 => 1,
            2 => 10,
            3 => 25,
            4 => 50,
            5 => 100,
            6 => 200,
            7 => 400,
            8 if low_power => 1620,
            9 if low_power => 5376,
            9 => 1344,
            _ => 0,
        }
    }

    /// The power and resolution mode in force.
    pub fn mode(&self) -> AccelMode {
        if self.odr_hz() == 0 {
            AccelMode::PowerDown
        } else if self.accel[reg::CTRL_REG4_A as usize] & CTRL4_HR != 0 {
            AccelMode::HighResolution
        } else if self.accel[reg::CTRL_REG1_A as usize] & CTRL1_LPEN != 0 {
            AccelMode::LowPower
        } else {
            AccelMode::Normal
        }
    }

    /// The full scale in force, ±g.
    pub fn full_scale_g(&self) -> u32 {
        2 << ((self.accel[reg::CTRL_REG4_A as usize] & CTRL4_FS) >> 4)
    }

    /// A register's value as stored, without a read's side effects
    /// (inspection); `device` is [`ACCEL_ADDRESS`] or [`MAG_ADDRESS`].
    pub fn register(&self, device: u8, register: u8) -> u8 {
        match device {
            ACCEL_ADDRESS => match register {
                reg::WHO_AM_I_A => WHO_AM_I_A_VALUE,
                r => self.accel.get(usize::from(r)).copied().unwrap_or(0),
            },
            MAG_ADDRESS => match register {
                reg::WHO_AM_I_M => WHO_AM_I_M_VALUE,
                r if r < MAG_FIRST => self.reserved_mag_read,
                r => self.mag_slot(r).map_or(0, |i| self.mag[i]),
            },
            _ => 0,
        }
    }

    fn mag_slot(&self, register: u8) -> Option<usize> {
        let i = usize::from(register.checked_sub(MAG_FIRST)?);
        (i < MAG_COUNT).then_some(i)
    }

    /// Makes the chip boot until `at_us` on its clock (power-up at 0): until
    /// then it acknowledges no transfer. 0 by default (ready at once).
    pub fn set_ready_at_us(&mut self, at_us: u64) {
        self.ready_at_us = at_us;
    }

    /// Whether a transfer to `address` is acknowledged.
    pub fn acknowledges(&self, address: u8) -> bool {
        self.now_us >= self.ready_at_us && (address == ACCEL_ADDRESS || address == MAG_ADDRESS)
    }

    /// Runs the sampling clock up to `now_us` (earlier times are ignored):
    /// latches a new sample when one is due and the output is not held.
    pub(crate) fn advance_to(&mut self, now_us: u64) {
        if now_us > self.now_us {
            self.now_us = now_us;
        }
        let odr = self.odr_hz();
        if odr == 0 || self.now_us < self.next_due_us || self.held() {
            return;
        }
        let elapsed = self.now_us.saturating_sub(self.epoch_us);
        let index = elapsed.saturating_mul(u64::from(odr)) / 1_000_000;
        let missed = index.saturating_sub(self.samples);
        self.samples = index;
        self.next_due_us = self.due(index.saturating_add(1), odr);
        if missed == 0 || self.source == SampleSource::Frozen {
            return;
        }
        self.latch(missed > 1);
    }

    /// When sample `index` (counted from the epoch, the first is 1) is due.
    fn due(&self, index: u64, odr: u32) -> u64 {
        let odr = u64::from(odr.max(1));
        let offset = index.saturating_mul(1_000_000).saturating_add(odr - 1) / odr;
        self.epoch_us.saturating_add(offset)
    }

    /// Block data update holds the output registers while an axis has been
    /// half read.
    fn held(&self) -> bool {
        self.accel[reg::CTRL_REG4_A as usize] & CTRL4_BDU != 0
            && self.half_read.iter().any(|&h| h == 1 || h == 2)
    }

    fn next_random(&mut self) -> u32 {
        // xorshift32: deterministic, good enough for garbage.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x
    }

    fn latch(&mut self, skipped: bool) {
        let mode = self.mode();
        let fs = self.full_scale_g();
        let sensor = self.placement.raw(self.tilt);
        for (axis, &mg) in sensor.iter().enumerate() {
            let raw = match self.source {
                SampleSource::Garbage => {
                    let bits = mode.bits().max(1);
                    let max = (1i32 << (bits - 1)) - 1;
                    let r = self.next_random();
                    let magnitude = max - (r % (max as u32 / 10 + 1)) as i32;
                    let value = if r & 0x8000_0000 != 0 {
                        -magnitude
                    } else {
                        magnitude
                    };
                    ((value << (16 - bits)) as i16) as u16
                }
                _ => quantise(mode, fs, mg),
            };
            let [lo, hi] = raw.to_le_bytes();
            let at = usize::from(reg::OUT_X_L_A) + 2 * axis;
            self.accel[at] = lo;
            self.accel[at + 1] = hi;
        }
        let status = &mut self.accel[reg::STATUS_REG_A as usize];
        let unread = *status & 0x07;
        let overrun = if skipped { 0x07 } else { unread };
        let mut new = 0x07 | STATUS_ZYXDA | (overrun << 4) | (*status & 0x70);
        if new & 0x70 == 0x70 {
            new |= STATUS_ZYXOR;
        }
        *status = new;
        self.half_read = [0; 3];
        self.latched = self.latched.wrapping_add(1);
    }

    /// An I²C write to `address`: the first byte is the sub-address, the rest
    /// are written from there (auto-increment: bit 7 of the sub-address on
    /// the accelerometer, always on the magnetometer). Writes to read-only
    /// or reserved registers are ignored. An empty write only addresses.
    pub(crate) fn i2c_write(&mut self, address: u8, bytes: &[u8]) {
        let Some((&sub, data)) = bytes.split_first() else {
            return;
        };
        match address {
            ACCEL_ADDRESS => {
                self.accel_pointer = sub;
                for &byte in data {
                    self.write_accel(self.accel_pointer & 0x7F, byte);
                    self.step_accel_pointer();
                }
            }
            MAG_ADDRESS => {
                self.mag_pointer = sub;
                for &byte in data {
                    self.write_mag(self.mag_pointer, byte);
                    self.mag_pointer = self.mag_pointer.wrapping_add(1);
                }
            }
            _ => {}
        }
    }

    /// An I²C read from `address`, from the register pointer on.
    pub(crate) fn i2c_read(&mut self, address: u8, buffer: &mut [u8]) {
        match address {
            ACCEL_ADDRESS => {
                for byte in buffer.iter_mut() {
                    *byte = self.read_accel(self.accel_pointer & 0x7F);
                    self.step_accel_pointer();
                }
            }
            MAG_ADDRESS => {
                for byte in buffer.iter_mut() {
                    *byte = self.register(MAG_ADDRESS, self.mag_pointer);
                    self.mag_pointer = self.mag_pointer.wrapping_add(1);
                }
            }
            _ => buffer.fill(0xFF),
        }
    }

    fn step_accel_pointer(&mut self) {
        if self.accel_pointer & AUTO_INCREMENT != 0 {
            let next = (self.accel_pointer & 0x7F).wrapping_add(1) & 0x7F;
            self.accel_pointer = AUTO_INCREMENT | next;
        }
    }

    fn write_accel(&mut self, register: u8, value: u8) {
        let writable =
            matches!(register, 0x1F..=0x26 | 0x2E | 0x30 | 0x32..=0x34 | 0x36..=0x38 | 0x3A..=0x3F);
        if !writable {
            return;
        }
        let old = self.accel[usize::from(register)];
        // BOOT (CTRL_REG5_A bit 7) reloads the trimming and clears itself.
        let value = if register == reg::CTRL_REG5_A {
            value & 0x7F
        } else {
            value
        };
        self.accel[usize::from(register)] = value;
        if register == reg::CTRL_REG1_A && (old ^ value) & (CTRL1_ODR | CTRL1_LPEN) != 0 {
            // A new rate (or power-up): the sampling clock starts over.
            self.epoch_us = self.now_us;
            self.samples = 0;
            let odr = self.odr_hz();
            self.next_due_us = self.due(1, odr);
        }
    }

    fn write_mag(&mut self, register: u8, value: u8) {
        let writable = matches!(register, 0x45..=0x4A | 0x60..=0x63 | 0x65..=0x66);
        if let (true, Some(i)) = (writable, self.mag_slot(register)) {
            self.mag[i] = value;
        }
    }

    fn read_accel(&mut self, register: u8) -> u8 {
        match register {
            reg::WHO_AM_I_A => WHO_AM_I_A_VALUE,
            reg::STATUS_REG_AUX_A | reg::OUT_TEMP_L_A | reg::OUT_TEMP_H_A => 0,
            reg::OUT_X_L_A..=reg::OUT_Z_H_A => {
                let offset = usize::from(register - reg::OUT_X_L_A);
                let axis = offset / 2;
                let big_endian = self.accel[reg::CTRL_REG4_A as usize] & CTRL4_BLE != 0;
                // The byte at the higher address is the MSB unless BLE.
                let msb = (offset % 2 == 1) != big_endian;
                let at = usize::from(reg::OUT_X_L_A) + 2 * axis + usize::from(msb);
                let value = self.accel[at];
                self.half_read[axis] |= if msb { 2 } else { 1 };
                if self.half_read[axis] == 3 {
                    self.half_read[axis] = 0;
                }
                if msb {
                    // Reading the MSB consumes the axis's new data.
                    let bit = 1u8 << axis;
                    self.accel[reg::STATUS_REG_A as usize] &=
                        !(bit | (bit << 4) | STATUS_ZYXDA | STATUS_ZYXOR);
                }
                value
            }
            // Reserved addresses (0x40..0x7F included) read 0.
            r => self.accel.get(usize::from(r)).copied().unwrap_or(0),
        }
    }
}
