//! The accelerometers micro:bit v1 boards were built with, as data: how each
//! is found (`WHO_AM_I`), how its samples turn into milli-g, and how its
//! axes sit on the board. The firmware (`boards/microbit-v1/src/sensor.rs`)
//! and the host tests read the same tables; the virtual chips
//! ([`super::virtual_nxp`]) describe their mounting in their own words, so a
//! sign error here shows as a wrong tilt in the tests.
//!
//! The early boards (v1.3, v1.3B) carry an NXP MMA8653FC (with a MAG3110
//! magnetometer); the v1.5 boards an ST LSM303AGR or an NXP FXOS8700CQ
//! (accelerometer and magnetometer in one). The DAL tells them apart by
//! probing each chip's `WHO_AM_I` register at its address
//! (`MicroBitAccelerometer::autoDetect`); so does the firmware, with
//! [`PROBES`].
//!
//! # Axis maps: from the micro:bit DAL's per-chip tables
//!
//! The DAL (lancaster-university/microbit-dal, `source/drivers/MMA8653.cpp`,
//! `FXOS8700.cpp`, `LSM303Accelerometer.cpp`) turns each chip's raw axes `c`
//! into east-north-up: MMA8653 and FXOS8700 `E = (−c_y, c_x, c_z)`, LSM303
//! `E = (−c_y, −c_x, c_z)`; then every chip goes through the same
//! `CoordinateSpace(SIMPLE_CARTESIAN, upside-down, 0°)`
//! (`source/types/CoordinateSystem.cpp`), which gives the documented
//! micro:bit frame `m = (−E_y, E_x, E_z)`. So the NXP chips read
//! `m = (−c_x, −c_y, c_z)` and the LSM303 `m = (c_x, −c_y, c_z)` (the v2's
//! LSM303AGR has the same, `board::accel_link::AXIS_MAP`). The game's board
//! frame is `(−m_x, −m_z, −m_y)` (`board::accel_link::AXIS_MAP`'s doc derives
//! it); hence the maps below.

use crate::board::accel_link::AXIS_MAP as V2_LSM303AGR_AXIS_MAP;
use crate::input::sensor::{AccelMg, Axis, AxisMap, AxisSource};

/// The accelerometers a micro:bit v1 may carry.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Accelerometer {
    /// NXP MMA8653FC (micro:bit v1.3, v1.3B).
    Mma8653fc,
    /// ST LSM303AGR (micro:bit v1.5).
    Lsm303agr,
    /// NXP FXOS8700CQ (micro:bit v1.5).
    Fxos8700cq,
}

/// One `WHO_AM_I` probe: read register `register` of the I²C device at
/// 7-bit address `address`; `id` identifies `chip`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Probe {
    /// The chip this probe finds.
    pub chip: Accelerometer,
    /// 7-bit I²C address.
    pub address: u8,
    /// The `WHO_AM_I` register.
    pub register: u8,
    /// Its value on that chip.
    pub id: u8,
}

/// The probes in the order the firmware tries them: the DAL's
/// (`MicroBitAccelerometer::autoDetect` in microbit-dal: MMA8653, then
/// LSM303, then FXOS8700). Addresses and IDs from the chips' datasheets, as
/// the DAL uses them (its 8-bit addresses 0x3A, 0x32, 0x3C). The order
/// matters on a v1.5 with an LSM303AGR: its magnetometer sits at 0x1E, the
/// FXOS8700CQ's address, where register 0x0D is reserved (LSM303AGR
/// datasheet, table 21) and reads a byte nobody documents; probing the
/// LSM303AGR's accelerometer first finds it before anything reads there.
/// The MMA8653FC stays first for QEMU's `microbit` machine, whose TWI stub
/// answers every read with a fixed sequence beginning 0x5A (the MMA8653FC's
/// identity) whatever the address: the first probe's read gets that 0x5A.
pub const PROBES: [Probe; 3] = [
    Probe {
        chip: Accelerometer::Mma8653fc,
        address: MMA8653FC.address,
        register: nxp::WHO_AM_I,
        id: MMA8653FC.who_am_i,
    },
    Probe {
        chip: Accelerometer::Lsm303agr,
        address: 0x19,
        register: 0x0F,
        id: 0x33,
    },
    Probe {
        chip: Accelerometer::Fxos8700cq,
        address: FXOS8700CQ.address,
        register: nxp::WHO_AM_I,
        id: FXOS8700CQ.who_am_i,
    },
];

impl Accelerometer {
    /// The chip's name.
    pub const fn name(self) -> &'static str {
        match self {
            Accelerometer::Mma8653fc => "MMA8653FC",
            Accelerometer::Lsm303agr => "LSM303AGR",
            Accelerometer::Fxos8700cq => "FXOS8700CQ",
        }
    }

    /// The name the demo logs after `accel=` (lower case).
    pub const fn tag(self) -> &'static str {
        match self {
            Accelerometer::Mma8653fc => "mma8653fc",
            Accelerometer::Lsm303agr => "lsm303agr",
            Accelerometer::Fxos8700cq => "fxos8700cq",
        }
    }

    /// Chip axes → board frame on the micro:bit v1 (module doc).
    pub(crate) const fn axis_map(self) -> AxisMap {
        match self {
            Accelerometer::Mma8653fc | Accelerometer::Fxos8700cq => NXP_AXIS_MAP,
            Accelerometer::Lsm303agr => LSM303AGR_AXIS_MAP,
        }
    }

    /// The NXP chip's register facts (`None` for the LSM303AGR, which the
    /// `lsm303agr` crate drives).
    pub const fn nxp(self) -> Option<&'static NxpChip> {
        match self {
            Accelerometer::Mma8653fc => Some(&MMA8653FC),
            Accelerometer::Fxos8700cq => Some(&FXOS8700CQ),
            Accelerometer::Lsm303agr => None,
        }
    }
}

/// The chip a probe's answer identifies: `read` is the byte `probe`'s
/// register read back (`None`: no answer, e.g. a NAK).
pub fn identify(probe: &Probe, read: Option<u8>) -> Option<Accelerometer> {
    (read == Some(probe.id)).then_some(probe.chip)
}

/// MMA8653FC and FXOS8700CQ axes → board frame: `m = (−c_x, −c_y, c_z)`
/// (module doc), board `= (−m_x, −m_z, −m_y) = (c_x, −c_z, c_y)`.
pub(crate) const NXP_AXIS_MAP: AxisMap = AxisMap {
    x: AxisSource::pos(Axis::X),
    y: AxisSource::neg(Axis::Z),
    z: AxisSource::pos(Axis::Y),
};

/// LSM303AGR axes → board frame on the v1.5: `m = (c_x, −c_y, c_z)`, board
/// `= (−c_x, −c_z, c_y)`: the v2's map (the DAL and CODAL agree).
pub(crate) const LSM303AGR_AXIS_MAP: AxisMap = V2_LSM303AGR_AXIS_MAP;

/// The register map both NXP chips share for their accelerometer (MMA8653FC
/// data sheet rev. 2 §6, FXOS8700CQ data sheet rev. 8 §14).
pub mod nxp {
    /// Data-ready and overwrite flags (`DR_STATUS` on the FXOS8700CQ with
    /// its FIFO off, the power-on state).
    pub const STATUS: u8 = 0x00;
    /// X output, most significant byte (then X LSB, Y MSB, …, Z LSB).
    pub(crate) const OUT_X_MSB: u8 = 0x01;
    /// FXOS8700CQ only: FIFO setup (`F_MODE`, bits 7:6; 0 is FIFO off,
    /// the power-on state). With the FIFO on, register 0x00 is `F_STATUS`
    /// (overflow, watermark, sample count) instead of `DR_STATUS`, and the
    /// output registers read the FIFO's oldest sample.
    pub const F_SETUP: u8 = 0x09;
    /// `F_SETUP`: the FIFO mode field.
    pub(crate) const F_MODE: u8 = 0xC0;
    /// Identity.
    pub const WHO_AM_I: u8 = 0x0D;
    /// Full-scale range.
    pub const XYZ_DATA_CFG: u8 = 0x0E;
    /// Data rate, fast read, active.
    pub const CTRL_REG1: u8 = 0x2A;
    /// Software reset, oversampling mode.
    pub const CTRL_REG2: u8 = 0x2B;
    /// FXOS8700CQ only: the magnetometer's hybrid mode (0: accelerometer
    /// only, the data rates of `CTRL_REG1` as listed).
    pub(crate) const M_CTRL_REG1: u8 = 0x5B;
    /// `STATUS`: a new X, Y and Z sample is available.
    pub const STATUS_ZYXDR: u8 = 0x08;
    /// `STATUS`: a new sample overwrote an unread one.
    pub const STATUS_ZYXOW: u8 = 0x80;
    /// `CTRL_REG1`: active (sampling); 0 is standby.
    pub const CTRL1_ACTIVE: u8 = 0x01;
    /// `CTRL_REG1`: 8-bit fast read (the firmware keeps it off).
    pub const CTRL1_F_READ: u8 = 0x02;
    /// `CTRL_REG1`: data-rate field (bits 5:3).
    pub(crate) const CTRL1_DR: u8 = 0x38;
    /// `CTRL_REG1`: 200 Hz (DR = 0b010; accelerometer-only on the FXOS).
    pub const CTRL1_DR_200HZ: u8 = 0x10;
    /// `CTRL_REG2`: software reset: every register back to its power-on
    /// value, whatever an earlier firmware left (a reflash resets the nRF,
    /// not the chip).
    pub const CTRL2_RST: u8 = 0x40;
    /// How long the firmware leaves the chip alone after setting
    /// [`CTRL2_RST`], µs: 1 ms, the FXOS8700CQ's figure (data sheet rev. 8,
    /// `CTRL_REG2` `rst`, as Zephyr's `fxos8700` driver quotes it: "the
    /// sensor requires us to wait 1 ms after a reset before attempting
    /// further communications"). The MMA8653FC's data sheet (rev. 2) gives
    /// no figure; Linux's `mma8452` driver, which resets the MMA865x family
    /// the same way, sees `RST` clear within ten polls 100–200 µs apart, so
    /// 1 ms covers it too.
    pub const RESET_WAIT_US: u32 = 1_000;
    /// `CTRL_REG2`: high-resolution oversampling (MODS = 0b10).
    pub const CTRL2_MODS_HIGH_RESOLUTION: u8 = 0x02;
    /// `XYZ_DATA_CFG`: full-scale field; 0 is ±2 g.
    pub(crate) const XYZ_FS: u8 = 0x03;
    /// Bytes of one burst read from [`STATUS`]: the status, then X, Y, Z.
    pub(crate) const BURST: usize = 7;
}

/// What differs between the two NXP chips.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NxpChip {
    /// The chip.
    pub chip: Accelerometer,
    /// 7-bit I²C address.
    pub address: u8,
    /// `WHO_AM_I`'s value.
    pub who_am_i: u8,
    /// Significant bits of a sample, left-justified in 16.
    pub bits: u32,
    /// Counts per g at ±2 g (the data sheets' sensitivity).
    pub(crate) counts_per_g: i32,
}

/// MMA8653FC: 0x1D, `WHO_AM_I` 0x5A, 10-bit samples, 256 counts/g at ±2 g
/// (3.9 mg per count).
pub const MMA8653FC: NxpChip = NxpChip {
    chip: Accelerometer::Mma8653fc,
    address: 0x1D,
    who_am_i: 0x5A,
    bits: 10,
    counts_per_g: 256,
};

/// FXOS8700CQ: 0x1E (SA1 = SA0 = 0 on the micro:bit), `WHO_AM_I` 0xC7,
/// 14-bit samples, 4096 counts/g at ±2 g (0.244 mg per count).
pub const FXOS8700CQ: NxpChip = NxpChip {
    chip: Accelerometer::Fxos8700cq,
    address: 0x1E,
    who_am_i: 0xC7,
    bits: 14,
    counts_per_g: 4096,
};

impl NxpChip {
    /// One axis: the MSB and LSB as read (left-justified two's complement)
    /// → milli-g, rounded to nearest.
    pub const fn mg(&self, msb: u8, lsb: u8) -> i32 {
        let raw = i16::from_be_bytes([msb, lsb]) as i32;
        let counts = raw >> (16 - self.bits);
        let scaled = counts * 1000;
        let half = self.counts_per_g / 2;
        if scaled >= 0 {
            (scaled + half) / self.counts_per_g
        } else {
            (scaled - half) / self.counts_per_g
        }
    }

    /// A burst read from [`nxp::STATUS`] → the sample in the chip's axes,
    /// milli-g, or `None` if no new sample was flagged.
    pub const fn sample(&self, burst: &[u8; nxp::BURST]) -> Option<AccelMg> {
        if burst[0] & nxp::STATUS_ZYXDR == 0 {
            return None;
        }
        Some(AccelMg::new(
            self.mg(burst[1], burst[2]),
            self.mg(burst[3], burst[4]),
            self.mg(burst[5], burst[6]),
        ))
    }

    /// The register writes that configure the chip after its soft reset
    /// ([`crate::board::microbit_v1::nxp_driver::configure`]), in order:
    /// standby first (the data sheets allow configuration only in standby;
    /// the reset leaves the chip there, a re-initialisation without one
    /// would not), ±2 g, high-resolution oversampling, (FXOS8700CQ)
    /// accelerometer only, then 200 Hz and active. Registers not written
    /// here keep the power-on values the reset gave them.
    pub const fn configuration(&self) -> &'static [(u8, u8)] {
        const MMA: [(u8, u8); 4] = [
            (nxp::CTRL_REG1, 0),
            (nxp::XYZ_DATA_CFG, 0),
            (nxp::CTRL_REG2, nxp::CTRL2_MODS_HIGH_RESOLUTION),
            (nxp::CTRL_REG1, nxp::CTRL1_DR_200HZ | nxp::CTRL1_ACTIVE),
        ];
        const FXOS: [(u8, u8); 5] = [
            (nxp::CTRL_REG1, 0),
            (nxp::XYZ_DATA_CFG, 0),
            (nxp::CTRL_REG2, nxp::CTRL2_MODS_HIGH_RESOLUTION),
            (nxp::M_CTRL_REG1, 0),
            (nxp::CTRL_REG1, nxp::CTRL1_DR_200HZ | nxp::CTRL1_ACTIVE),
        ];
        match self.chip {
            Accelerometer::Fxos8700cq => &FXOS,
            _ => &MMA,
        }
    }
}

/// The sample rate both NXP chips are set to, Hz (`CTRL1_DR_200HZ`): the
/// v2's LSM303AGR rate, twice the 100 Hz poll.
pub(crate) const NXP_ODR_HZ: u32 = 200;

// The LSM303AGR path runs at the same rate (input::lsm303 checks its own).
const _: () = assert!(NXP_ODR_HZ == crate::input::accel_timing::ACCEL_ODR_HZ);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_at_the_ends_of_the_range() {
        // MMA8653FC: +1 g = 256 counts = 0x4000 left-justified.
        assert_eq!(MMA8653FC.mg(0x40, 0x00), 1000);
        assert_eq!(MMA8653FC.mg(0xC0, 0x00), -1000);
        // One count: 3.90625 mg, rounded.
        assert_eq!(MMA8653FC.mg(0x00, 0x40), 4);
        assert_eq!(MMA8653FC.mg(0xFF, 0xC0), -4);
        // The low six bits are not data.
        assert_eq!(MMA8653FC.mg(0x40, 0x3F), 1000);
        // Full scale: 511 and -512 counts.
        assert_eq!(MMA8653FC.mg(0x7F, 0xC0), 1996);
        assert_eq!(MMA8653FC.mg(0x80, 0x00), -2000);
        // FXOS8700CQ: +1 g = 4096 counts = 0x4000 left-justified too.
        assert_eq!(FXOS8700CQ.mg(0x40, 0x00), 1000);
        assert_eq!(FXOS8700CQ.mg(0x00, 0x04), 0);
        assert_eq!(FXOS8700CQ.mg(0x00, 0x08), 0);
        assert_eq!(FXOS8700CQ.mg(0x00, 0x10), 1);
        assert_eq!(FXOS8700CQ.mg(0x80, 0x00), -2000);
        assert_eq!(FXOS8700CQ.mg(0x7F, 0xFC), 2000);
    }

    #[test]
    fn no_sample_without_data_ready() {
        let burst = [0x00, 0x40, 0, 0, 0, 0, 0];
        assert_eq!(MMA8653FC.sample(&burst), None);
        let burst = [nxp::STATUS_ZYXDR, 0x40, 0, 0xC0, 0, 0x20, 0];
        assert_eq!(
            MMA8653FC.sample(&burst),
            Some(AccelMg::new(1000, -1000, 500))
        );
    }

    #[test]
    fn the_maps_are_permutations() {
        for chip in [
            Accelerometer::Mma8653fc,
            Accelerometer::Fxos8700cq,
            Accelerometer::Lsm303agr,
        ] {
            assert!(chip.axis_map().is_permutation(), "{chip:?}");
        }
    }

    #[test]
    fn probes_match_the_chip_tables() {
        for probe in PROBES {
            if let Some(nxp) = probe.chip.nxp() {
                assert_eq!((probe.address, probe.id), (nxp.address, nxp.who_am_i));
            }
            assert_eq!(identify(&probe, Some(probe.id)), Some(probe.chip));
            assert_eq!(identify(&probe, None), None);
            assert_eq!(identify(&probe, Some(probe.id ^ 1)), None);
        }
        // QEMU's stub answers the first read with 0x5A: the MMA8653FC.
        assert_eq!(
            identify(&PROBES[0], Some(0x5A)),
            Some(Accelerometer::Mma8653fc)
        );
    }
}
