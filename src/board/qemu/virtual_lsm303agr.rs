//! A virtual LSM303AGR: the accelerometer's registers as the `lsm303agr`
//! driver (1.1) uses them, serving a tilt that a keyboard or a script sets,
//! and the faults a real chip on a real bus shows, injected at run time.
//!
//! The QEMU board has no accelerometer, so without this its input stack
//! (driver, [`TiltPipeline`](crate::input::sensor::TiltPipeline) supervision)
//! would run nowhere but on a micro:bit. The chip sits on a virtual I²C bus,
//! [`VirtualTwim`](super::virtual_i2c::VirtualTwim), which adds the bus
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
//!   on the caller's clock ([`VirtualLsm303agr::advance_to`]). A new sample
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
//!   own table, `board::microbit::AXIS_MAP`; the two are written apart, so a
//!   sign or axis wrong in either reads a wrong tilt in the tests and in QEMU.
//! * Power-on values: `CTRL_REG1_A` = 0x07 (power-down, axes enabled), the
//!   other control registers 0, no data ready; [`VirtualLsm303agr::power_on_reset`]
//!   brings them back (the injected chip reset).
//! * Magnetometer (I²C address [`MAG_ADDRESS`]): only enough for the driver's
//!   `init()` (it writes `CFG_REG_C_M`): `WHO_AM_I_M` (0x40), the
//!   configuration registers stored; its outputs read 0.
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

use core::sync::atomic::{AtomicI16, AtomicU32, AtomicU8, Ordering};

use crate::input::event::Tilt;
use crate::input::sensor::{Axis, AxisMap, AxisSource};

/// The accelerometer's 7-bit I²C address.
pub const ACCEL_ADDRESS: u8 = 0x19;
/// The magnetometer's 7-bit I²C address.
pub const MAG_ADDRESS: u8 = 0x1E;
/// What `WHO_AM_I_A` reads.
pub const WHO_AM_I_A_VALUE: u8 = 0x33;
/// What `WHO_AM_I_M` reads.
pub const WHO_AM_I_M_VALUE: u8 = 0x40;
/// Sub-address bit 7: auto-increment the register pointer (accelerometer).
pub const AUTO_INCREMENT: u8 = 0x80;

/// Register addresses (datasheet table 21).
pub mod reg {
    /// Temperature status.
    pub const STATUS_REG_AUX_A: u8 = 0x07;
    /// Temperature output, low byte.
    pub const OUT_TEMP_L_A: u8 = 0x0C;
    /// Temperature output, high byte.
    pub const OUT_TEMP_H_A: u8 = 0x0D;
    /// Accelerometer identity.
    pub const WHO_AM_I_A: u8 = 0x0F;
    /// Temperature sensor enable.
    pub const TEMP_CFG_REG_A: u8 = 0x1F;
    /// ODR, low-power enable, axis enables.
    pub const CTRL_REG1_A: u8 = 0x20;
    /// High-pass filter.
    pub const CTRL_REG2_A: u8 = 0x21;
    /// INT1 routing.
    pub const CTRL_REG3_A: u8 = 0x22;
    /// BDU, BLE, full scale, high resolution, self-test, SPI mode.
    pub const CTRL_REG4_A: u8 = 0x23;
    /// Boot, FIFO enable, interrupt latching.
    pub const CTRL_REG5_A: u8 = 0x24;
    /// INT2 routing.
    pub const CTRL_REG6_A: u8 = 0x25;
    /// Reference for the interrupt generation.
    pub const REFERENCE_A: u8 = 0x26;
    /// Data ready and overrun flags.
    pub const STATUS_REG_A: u8 = 0x27;
    /// X output, low byte (the first of six: X, Y, Z, low byte first).
    pub const OUT_X_L_A: u8 = 0x28;
    /// Z output, high byte (the last of six).
    pub const OUT_Z_H_A: u8 = 0x2D;
    /// FIFO mode and threshold.
    pub const FIFO_CTRL_REG_A: u8 = 0x2E;
    /// Magnetometer identity.
    pub const WHO_AM_I_M: u8 = 0x4F;
    /// Magnetometer configuration A (mode, ODR, reset).
    pub const CFG_REG_A_M: u8 = 0x60;
    /// Magnetometer configuration B (filter, offset cancellation).
    pub const CFG_REG_B_M: u8 = 0x61;
    /// Magnetometer configuration C (BDU, interrupt pin).
    pub const CFG_REG_C_M: u8 = 0x62;
}

/// `CTRL_REG1_A`: output data rate bits.
pub const CTRL1_ODR: u8 = 0xF0;
/// `CTRL_REG1_A`: low-power mode.
pub const CTRL1_LPEN: u8 = 0x08;
/// `CTRL_REG4_A`: block data update.
pub const CTRL4_BDU: u8 = 0x80;
/// `CTRL_REG4_A`: big-endian output (MSB at the lower address).
pub const CTRL4_BLE: u8 = 0x40;
/// `CTRL_REG4_A`: full-scale bits.
pub const CTRL4_FS: u8 = 0x30;
/// `CTRL_REG4_A`: high-resolution mode.
pub const CTRL4_HR: u8 = 0x08;
/// `STATUS_REG_A`: a new X, Y and Z sample is available.
pub const STATUS_ZYXDA: u8 = 0x08;
/// `STATUS_REG_A`: a new X, Y and Z sample overwrote an unread one.
pub const STATUS_ZYXOR: u8 = 0x80;
/// `CTRL_REG1_A` at power-on: power-down, every axis enabled.
pub const CTRL_REG1_A_RESET: u8 = 0x07;
/// `CFG_REG_A_M` at power-on: idle mode.
pub const CFG_REG_A_M_RESET: u8 = 0x03;

/// The accelerometer's power and resolution mode.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelMode {
    /// No conversions (ODR 0).
    PowerDown,
    /// 8-bit samples.
    LowPower,
    /// 10-bit samples.
    Normal,
    /// 12-bit samples.
    HighResolution,
}

impl AccelMode {
    /// Significant bits of a sample (0 when powered down).
    pub const fn bits(self) -> u32 {
        match self {
            AccelMode::PowerDown => 0,
            AccelMode::LowPower => 8,
            AccelMode::Normal => 10,
            AccelMode::HighResolution => 12,
        }
    }

    /// Milli-g per LSB at full scale ±`full_scale_g` g, as the `lsm303agr`
    /// driver converts back (0 when powered down).
    pub const fn mg_per_lsb(self, full_scale_g: u32) -> i32 {
        let fs = full_scale_g as i32;
        match self {
            AccelMode::PowerDown => 0,
            AccelMode::LowPower => fs * 8,
            AccelMode::Normal => fs * 2,
            AccelMode::HighResolution => fs / 2,
        }
    }
}

/// A sample in milli-g, quantised as the chip outputs it in `mode` at
/// ±`full_scale_g` g: rounded to the nearest LSB, saturated at the mode's
/// range, left-justified in 16 bits (two's complement).
pub const fn quantise(mode: AccelMode, full_scale_g: u32, mg: i32) -> u16 {
    let bits = mode.bits();
    let step = mode.mg_per_lsb(full_scale_g);
    if bits == 0 || step <= 0 {
        return 0;
    }
    let half = step / 2;
    let lsb = if mg >= 0 {
        mg.saturating_add(half) / step
    } else {
        mg.saturating_sub(half) / step
    };
    let max = (1i32 << (bits - 1)) - 1;
    let min = -(1i32 << (bits - 1));
    let lsb = if lsb > max {
        max
    } else if lsb < min {
        min
    } else {
        lsb
    };
    ((lsb << (16 - bits)) as i16) as u16
}

/// Where a chip's axes point on the board: for each chip axis, the board axis
/// (`x` right, `y` up out of the LEDs, `z` towards the player) it lies along,
/// negated when it points the other way. At rest a chip axis reads the
/// board-frame reading along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Placement {
    /// The board direction of the chip's `x`.
    pub x: AxisSource,
    /// The board direction of the chip's `y`.
    pub y: AxisSource,
    /// The board direction of the chip's `z`.
    pub z: AxisSource,
}

impl Placement {
    /// The placement a board's firmware table assumes (its inverse): for a
    /// board with no table of the chip's own, where a sign error cannot show.
    pub const fn assumed_by(map: &AxisMap) -> Placement {
        let sources = [map.x, map.y, map.z];
        let board_axes = [Axis::X, Axis::Y, Axis::Z];
        let mut chip = [AxisSource::pos(Axis::X); 3];
        let mut i = 0;
        while i < 3 {
            let slot = match sources[i].axis {
                Axis::X => 0,
                Axis::Y => 1,
                Axis::Z => 2,
            };
            chip[slot] = AxisSource {
                axis: board_axes[i],
                negate: sources[i].negate,
            };
            i += 1;
        }
        Placement {
            x: chip[0],
            y: chip[1],
            z: chip[2],
        }
    }

    /// A board-frame reading in the chip's axes.
    pub const fn raw(&self, board: [i32; 3]) -> [i32; 3] {
        let chip = [self.x, self.y, self.z];
        let mut raw = [0i32; 3];
        let mut i = 0;
        while i < 3 {
            let value = board[match chip[i].axis {
                Axis::X => 0,
                Axis::Y => 1,
                Axis::Z => 2,
            }];
            raw[i] = if chip[i].negate {
                value.saturating_neg()
            } else {
                value
            };
            i += 1;
        }
        raw
    }
}

/// The LSM303AGR on the micro:bit v2, in the chip's terms: its `x` points to
/// the left edge (button A), its `y` to the edge connector (the player), its
/// `z` out of the back (the chip sits on the back of the board). Read off the
/// raw readings of a board held in each orientation, as the micro:bit runtime
/// (CODAL's LSM303 driver with its upside-down coordinate space) and the Rust
/// "micro:bit v2 book" give them: raw x +1 g with the right edge down, raw y
/// +1 g with the logo edge down, raw z +1 g lying screen-down; an axis reads
/// +1 g when it points up. Not derived from the firmware's `AXIS_MAP`.
pub const MICROBIT_V2: Placement = Placement {
    x: AxisSource::neg(Axis::X),
    y: AxisSource::pos(Axis::Z),
    z: AxisSource::neg(Axis::Y),
};

/// A board-frame reading expressed in the chip's axes: the inverse of `map`
/// (which gives each board axis from a sensor axis and a sign).
pub const fn to_sensor_frame(map: &AxisMap, board: [i32; 3]) -> [i32; 3] {
    let mut raw = [0i32; 3];
    let sources = [map.x, map.y, map.z];
    let mut i = 0;
    while i < 3 {
        let value = if sources[i].negate {
            board[i].saturating_neg()
        } else {
            board[i]
        };
        let axis = match sources[i].axis {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        };
        raw[axis] = value;
        i += 1;
    }
    raw
}

/// A fault injected into the virtual chip or its bus.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum InjectedFault {
    /// Everything works.
    Healthy = 0,
    /// Nothing acknowledges its address: every transfer fails at once.
    Nak = 1,
    /// A transfer starts and never completes (a slave holding SDA low): the
    /// transfer's future stays pending; only the caller's timeout ends it.
    StuckBus = 2,
    /// Conversions stall: the output registers keep their last values and no
    /// new data is flagged; writes are accepted, a re-init does not help.
    FrozenData = 3,
    /// Every new sample is random, in the top tenth of the full scale on
    /// every axis: implausible.
    Garbage = 4,
    /// The chip resets once (a brown-out): its registers go back to their
    /// power-on values (powered down, no data) and the fault is over; the
    /// driver has to initialise it again.
    ChipReset = 5,
}

impl InjectedFault {
    /// Every fault, in key order (`0` to `5`).
    pub const ALL: [InjectedFault; 6] = [
        InjectedFault::Healthy,
        InjectedFault::Nak,
        InjectedFault::StuckBus,
        InjectedFault::FrozenData,
        InjectedFault::Garbage,
        InjectedFault::ChipReset,
    ];

    /// The fault with this number (its key), if any.
    pub const fn from_u8(value: u8) -> Option<InjectedFault> {
        if (value as usize) < Self::ALL.len() {
            Some(Self::ALL[value as usize])
        } else {
            None
        }
    }

    /// A short name for logs and the status line.
    pub const fn name(self) -> &'static str {
        match self {
            InjectedFault::Healthy => "healthy",
            InjectedFault::Nak => "NAK",
            InjectedFault::StuckBus => "stuck bus",
            InjectedFault::FrozenData => "frozen data",
            InjectedFault::Garbage => "garbage",
            InjectedFault::ChipReset => "chip reset",
        }
    }
}

/// What the virtual chip is given from outside, and what its bus counts:
/// shared (`&`) between whoever sets the tilt and injects faults (terminal
/// keys, a script, a test) and the [`VirtualTwim`](super::virtual_i2c::VirtualTwim)
/// that applies them to the chip at each transfer.
///
/// Atomics with plain loads and stores (no read-modify-write, so it builds
/// for the Cortex-M0 too): the firmware runs its tasks on one core without
/// preemption between them, so the three components of a tilt are never
/// seen half written.
#[derive(Debug)]
pub struct ChipControl {
    tilt: [AtomicI16; 3],
    fault: AtomicU8,
    reset_requests: AtomicU32,
    transfers: AtomicU32,
    refused: AtomicU32,
    resets_applied: AtomicU32,
}

impl ChipControl {
    /// A flat board, healthy, nothing counted.
    pub const fn new() -> Self {
        Self {
            tilt: [
                AtomicI16::new(Tilt::FLAT.x),
                AtomicI16::new(Tilt::FLAT.y),
                AtomicI16::new(Tilt::FLAT.z),
            ],
            fault: AtomicU8::new(InjectedFault::Healthy as u8),
            reset_requests: AtomicU32::new(0),
            transfers: AtomicU32::new(0),
            refused: AtomicU32::new(0),
            resets_applied: AtomicU32::new(0),
        }
    }

    /// Sets the tilt (board frame, milli-g) the chip samples from now on.
    pub fn set_tilt(&self, tilt: Tilt) {
        self.tilt[0].store(tilt.x, Ordering::Relaxed);
        self.tilt[1].store(tilt.y, Ordering::Relaxed);
        self.tilt[2].store(tilt.z, Ordering::Relaxed);
    }

    /// The tilt the chip samples.
    pub fn tilt(&self) -> Tilt {
        Tilt {
            x: self.tilt[0].load(Ordering::Relaxed),
            y: self.tilt[1].load(Ordering::Relaxed),
            z: self.tilt[2].load(Ordering::Relaxed),
        }
    }

    /// Injects `fault` (replacing the one in force). [`InjectedFault::ChipReset`]
    /// is an event: it ends the fault in force and resets the chip once, at
    /// its next transfer.
    pub fn inject(&self, fault: InjectedFault) {
        if fault == InjectedFault::ChipReset {
            let requests = self.reset_requests.load(Ordering::Relaxed);
            self.reset_requests
                .store(requests.wrapping_add(1), Ordering::Relaxed);
            self.fault
                .store(InjectedFault::Healthy as u8, Ordering::Relaxed);
        } else {
            self.fault.store(fault as u8, Ordering::Relaxed);
        }
    }

    /// The fault in force ([`InjectedFault::Healthy`] after a chip reset).
    pub fn fault(&self) -> InjectedFault {
        InjectedFault::from_u8(self.fault.load(Ordering::Relaxed)).unwrap_or(InjectedFault::Healthy)
    }

    /// Chip resets asked for so far.
    pub fn reset_requests(&self) -> u32 {
        self.reset_requests.load(Ordering::Relaxed)
    }

    /// Chip resets the chip went through so far.
    pub fn resets_applied(&self) -> u32 {
        self.resets_applied.load(Ordering::Relaxed)
    }

    /// Transfers that reached the bus (acknowledged or not; a stuck one
    /// counts when it starts).
    pub fn transfers(&self) -> u32 {
        self.transfers.load(Ordering::Relaxed)
    }

    /// Transfers refused before reaching the bus (the DMA rule, lengths).
    pub fn refused(&self) -> u32 {
        self.refused.load(Ordering::Relaxed)
    }

    fn bump(counter: &AtomicU32) {
        counter.store(
            counter.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }

    pub(crate) fn count_transfer(&self) {
        Self::bump(&self.transfers);
    }

    pub(crate) fn count_refused(&self) {
        Self::bump(&self.refused);
    }

    pub(crate) fn count_reset(&self) {
        Self::bump(&self.resets_applied);
    }
}

impl Default for ChipControl {
    fn default() -> Self {
        Self::new()
    }
}

/// Where new samples come from.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleSource {
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
/// from its bus ([`VirtualTwim`](super::virtual_i2c::VirtualTwim)), which
/// also feeds it the time ([`VirtualLsm303agr::advance_to`]), the tilt and
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
    tilt_mg: [i32; 3],
    source: SampleSource,
    rng: u32,
    /// Samples latched since power-on (diagnostics).
    latched: u32,
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
            tilt_mg: [
                Tilt::FLAT.x as i32,
                Tilt::FLAT.y as i32,
                Tilt::FLAT.z as i32,
            ],
            source: SampleSource::Tilt,
            rng: 0x2545_f491,
            latched: 0,
        };
        chip.accel[reg::CTRL_REG1_A as usize] = CTRL_REG1_A_RESET;
        chip.mag[(reg::CFG_REG_A_M - MAG_FIRST) as usize] = CFG_REG_A_M_RESET;
        chip
    }

    /// Back to the power-on state (registers, outputs, flags, pointers); the
    /// clock, the tilt and the sample source are kept.
    pub fn power_on_reset(&mut self) {
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

    /// Sets the tilt (board frame, milli-g) the next samples take.
    pub fn set_tilt_mg(&mut self, tilt_mg: [i32; 3]) {
        self.tilt_mg = tilt_mg;
    }

    /// Sets where the next samples come from.
    pub fn set_source(&mut self, source: SampleSource) {
        self.source = source;
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
                r => self.mag_slot(r).map_or(0, |i| self.mag[i]),
            },
            _ => 0,
        }
    }

    fn mag_slot(&self, register: u8) -> Option<usize> {
        let i = usize::from(register.checked_sub(MAG_FIRST)?);
        (i < MAG_COUNT).then_some(i)
    }

    /// Whether a transfer to `address` is acknowledged.
    pub fn acknowledges(&self, address: u8) -> bool {
        address == ACCEL_ADDRESS || address == MAG_ADDRESS
    }

    /// Runs the sampling clock up to `now_us` (earlier times are ignored):
    /// latches a new sample when one is due and the output is not held.
    pub fn advance_to(&mut self, now_us: u64) {
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
        let sensor = self.placement.raw(self.tilt_mg);
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
    pub fn i2c_write(&mut self, address: u8, bytes: &[u8]) {
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
    pub fn i2c_read(&mut self, address: u8, buffer: &mut [u8]) {
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
