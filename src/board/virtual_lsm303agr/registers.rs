//! The LSM303AGR's accelerometer registers as the virtual chip models them
//! (the datasheet's register map, table 21): addresses, identities, the
//! control and status bits the driver uses, the power and resolution modes,
//! and how a reading in milli-g becomes an output word.

/// The accelerometer's 7-bit I²C address.
pub const ACCEL_ADDRESS: u8 = 0x19;
/// The magnetometer's 7-bit I²C address.
pub const MAG_ADDRESS: u8 = 0x1E;
/// What `WHO_AM_I_A` reads.
pub(crate) const WHO_AM_I_A_VALUE: u8 = 0x33;
/// What `WHO_AM_I_M` reads.
pub(crate) const WHO_AM_I_M_VALUE: u8 = 0x40;
/// Sub-address bit 7: auto-increment the register pointer (accelerometer).
pub(crate) const AUTO_INCREMENT: u8 = 0x80;

/// Register addresses (datasheet table 21).
pub mod reg {
    /// Temperature status.
    pub(crate) const STATUS_REG_AUX_A: u8 = 0x07;
    /// Temperature output, low byte.
    pub(crate) const OUT_TEMP_L_A: u8 = 0x0C;
    /// Temperature output, high byte.
    pub(crate) const OUT_TEMP_H_A: u8 = 0x0D;
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
    pub(crate) const CTRL_REG5_A: u8 = 0x24;
    /// INT2 routing.
    pub const CTRL_REG6_A: u8 = 0x25;
    /// Reference for the interrupt generation.
    pub const REFERENCE_A: u8 = 0x26;
    /// Data ready and overrun flags.
    pub const STATUS_REG_A: u8 = 0x27;
    /// X output, low byte (the first of six: X, Y, Z, low byte first).
    pub(crate) const OUT_X_L_A: u8 = 0x28;
    /// Z output, high byte (the last of six).
    pub(crate) const OUT_Z_H_A: u8 = 0x2D;
    /// FIFO mode and threshold.
    pub const FIFO_CTRL_REG_A: u8 = 0x2E;
    /// Magnetometer identity.
    pub(crate) const WHO_AM_I_M: u8 = 0x4F;
    /// Magnetometer configuration A (mode, ODR, reset).
    pub(crate) const CFG_REG_A_M: u8 = 0x60;
    /// Magnetometer configuration B (filter, offset cancellation).
    pub const CFG_REG_B_M: u8 = 0x61;
    /// Magnetometer configuration C (BDU, interrupt pin).
    pub const CFG_REG_C_M: u8 = 0x62;
}

/// `CTRL_REG1_A`: output data rate bits.
pub(crate) const CTRL1_ODR: u8 = 0xF0;
/// `CTRL_REG1_A`: low-power mode.
pub(crate) const CTRL1_LPEN: u8 = 0x08;
/// `CTRL_REG4_A`: block data update.
pub const CTRL4_BDU: u8 = 0x80;
/// `CTRL_REG4_A`: big-endian output (MSB at the lower address).
pub(crate) const CTRL4_BLE: u8 = 0x40;
/// `CTRL_REG4_A`: full-scale bits.
pub(crate) const CTRL4_FS: u8 = 0x30;
/// `CTRL_REG4_A`: high-resolution mode.
pub(crate) const CTRL4_HR: u8 = 0x08;
/// `STATUS_REG_A`: a new X, Y and Z sample is available.
pub(crate) const STATUS_ZYXDA: u8 = 0x08;
/// `STATUS_REG_A`: a new X, Y and Z sample overwrote an unread one.
pub(crate) const STATUS_ZYXOR: u8 = 0x80;
/// `CTRL_REG1_A` at power-on: power-down, every axis enabled.
pub const CTRL_REG1_A_RESET: u8 = 0x07;
/// `CFG_REG_A_M` at power-on: idle mode.
pub(crate) const CFG_REG_A_M_RESET: u8 = 0x03;

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
pub(crate) const fn quantise(mode: AccelMode, full_scale_g: u32, mg: i32) -> u16 {
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
