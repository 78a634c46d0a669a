//! Virtual MMA8653FC and FXOS8700CQ: with the virtual LSM303AGR (shared with
//! the QEMU board) as a v1.5 carries it, the chips of a virtual v1 TWI
//! ([`super::virtual_twi`]). The v1's sensor stack (probe,
//! [`super::nxp_driver`], [`Recovering`](crate::board::i2c::Recovering), the
//! supervision) runs against them on the host, with the fidelity rules of the
//! virtual LSM303AGR (`board::virtual_lsm303agr`) and its
//! [`ChipControl`] for the tilt and the injected faults.
//!
//! # What is modelled (MMA8653FC data sheet rev. 2, FXOS8700CQ rev. 8)
//!
//! * Identity: `WHO_AM_I` (0x0D) reads 0x5A / 0xC7; only the chip's address
//!   acknowledges.
//! * Burst reads and writes: the register pointer is set by the first byte
//!   written and advances by one per byte (the wrap after `OUT_Z_LSB` and the
//!   8-bit fast read are not modelled: the driver uses neither).
//! * Standby and active: `CTRL_REG1`'s `ACTIVE` bit. In active mode the
//!   configuration registers (`XYZ_DATA_CFG`, `CTRL_REG2`'s oversampling
//!   bits, `M_CTRL_REG1`, `F_SETUP`, the interrupt registers `CTRL_REG4` and
//!   `CTRL_REG5` (stored, without effect), the rest of `CTRL_REG1`) ignore
//!   writes, as the data
//!   sheets require them written in standby. `CTRL_REG2`'s `RST` resets the
//!   chip at any time: every register back to power-on, then nothing is
//!   acknowledged for [`RESET_US`]; the FXOS8700CQ does not acknowledge the
//!   byte that set `RST` either (Linux's `mma8452` driver and Zephyr's
//!   `fxos8700` driver both note it; the model gives the MMA8653FC the
//!   acknowledge and the same reset time, for want of a figure of its own).
//! * Kept across a "reflash": the chip is powered by the board, not reset
//!   by the nRF, so a new firmware finds every register as the last one
//!   left it (a test carries the chip's state from one
//!   [`VirtualTwi`](super::virtual_twi::VirtualTwi) to the next with its `chip`).
//! * FXOS8700CQ FIFO (`F_SETUP`, written in standby; FXOS8700CQ data sheet
//!   rev. 8, `F_SETUP` and `F_STATUS`): with `F_MODE` non-zero every new
//!   sample goes into a 32-sample FIFO (circular and trigger modes drop the
//!   oldest when full, fill mode drops the new one; both set `F_OVF`),
//!   register 0x00 reads `F_STATUS` (`F_OVF` bit 7, the sample count in
//!   bits 5:0; the watermark flag is not modelled), and the output
//!   registers read the oldest sample, which a read through `OUT_Z_LSB`
//!   takes out. Going active flushes it.
//! * Data rate from `CTRL_REG1`'s `DR` (800 Hz to 1.56 Hz), the first sample
//!   one period after going active; a new sample sets `ZYXDR` (and `ZYXOW`
//!   if the previous one was unread); reading the three MSBs clears them.
//! * Samples: the tilt (board frame, milli-g) turned into the chip's axes by
//!   `MOUNTING` — the chip's place on the board in its own words, not the
//!   firmware's axis map — quantised at the range in force (±2/4/8 g) to the
//!   chip's 10 or 14 bits, left-justified, MSB first. Counts per g are
//!   derived here from the bit count and the range, not taken from the
//!   firmware's table.
//! * Power-on: everything 0 (standby, no data).
//!
//! Faults ([`InjectedFault`], from the shared [`ChipControl`]): NAK (no
//! acknowledge), a stuck bus (every transfer times out — the v1 TWI's
//! deadline — and the bus **stays** stuck after the fault is lifted until it
//! is cleared: nine clocks and a STOP), frozen data (no new samples, writes
//! accepted), garbage (new samples at the top tenth of the range on every
//! axis: implausible), a chip reset (registers back to power-on at the next
//! transfer).

use super::accel::{nxp, Accelerometer};
#[cfg(doc)]
use crate::board::virtual_lsm303agr::{ChipControl, InjectedFault};
use crate::input::axes::AccelMg;

/// The NXP chips' placement on the v1 (both sit on the back of the board,
/// the same way round): for chip axis X, Y, Z, the board axis it points
/// along (0 = x right, 1 = y out of the LEDs, 2 = z towards the player) and
/// its sign. From the DAL's tables (`MMA8653.cpp`, `FXOS8700.cpp`: east =
/// −Y, north = X, up = Z; `CoordinateSystem.cpp`'s upside-down micro:bit
/// frame), restated as directions: X along the board's right, Y towards the
/// edge connector, Z out of the back (a flat board, screen up, reads −1 g on
/// Z).
pub(crate) const MOUNTING: [(usize, i32); 3] = [(0, 1), (2, 1), (1, -1)];

/// `CTRL_REG4` (interrupt enables) and `CTRL_REG5` (interrupt routing):
/// stored, without effect (the firmware polls); the DAL sets both to route
/// data-ready to INT1, so a board that ran a DAL program before has them
/// non-zero.
const CTRL_REG4: u8 = 0x2D;
const CTRL_REG5: u8 = 0x2E;

/// Registers modelled (0x00..0x80).
const REGISTERS: usize = 0x80;

/// How long a chip answers nothing after a soft reset, µs: the FXOS8700CQ's
/// 1 ms (data sheet rev. 8, `CTRL_REG2` `rst`, as Zephyr's `fxos8700` driver
/// quotes it), taken for both chips.
pub const RESET_US: u64 = 1_000;

/// Depth of the FXOS8700CQ's FIFO, samples.
const FIFO_DEPTH: usize = 32;

/// A virtual MMA8653FC or FXOS8700CQ.
#[derive(Clone, Debug)]
pub struct VirtualNxp {
    pub(super) chip: Accelerometer,
    regs: [u8; REGISTERS],
    pointer: u8,
    now_us: u64,
    next_due_us: u64,
    /// Bit per axis: MSB read since the last sample.
    msb_read: u8,
    tilt: AccelMg,
    frozen: bool,
    garbage: bool,
    rng: u32,
    latched: u32,
    /// Until this time the chip is resetting and acknowledges nothing.
    resetting_until_us: u64,
    /// The FXOS8700CQ's FIFO: output bytes of each sample, oldest first.
    fifo: [[u8; 6]; FIFO_DEPTH],
    fifo_len: usize,
    fifo_overflow: bool,
}

impl VirtualNxp {
    /// A chip at power-on. `chip` is [`Accelerometer::Mma8653fc`] or
    /// [`Accelerometer::Fxos8700cq`] (anything else is taken as the MMA8653FC).
    pub const fn new(chip: Accelerometer) -> Self {
        Self {
            chip,
            regs: [0; REGISTERS],
            pointer: 0,
            now_us: 0,
            next_due_us: 0,
            msb_read: 0,
            tilt: AccelMg::LEVEL,
            frozen: false,
            garbage: false,
            rng: 0x2545_f491,
            latched: 0,
            resetting_until_us: 0,
            fifo: [[0; 6]; FIFO_DEPTH],
            fifo_len: 0,
            fifo_overflow: false,
        }
    }

    /// The 7-bit address it answers.
    pub const fn address(&self) -> u8 {
        match self.chip {
            Accelerometer::Fxos8700cq => 0x1E,
            _ => 0x1D,
        }
    }

    /// `WHO_AM_I`'s value.
    pub const fn who_am_i(&self) -> u8 {
        match self.chip {
            Accelerometer::Fxos8700cq => 0xC7,
            _ => 0x5A,
        }
    }

    /// Bits per sample.
    pub const fn bits(&self) -> u32 {
        match self.chip {
            Accelerometer::Fxos8700cq => 14,
            _ => 10,
        }
    }

    /// Full scale in force, ±g (2, 4 or 8).
    pub const fn full_scale_g(&self) -> i32 {
        match self.regs[nxp::XYZ_DATA_CFG as usize] & nxp::XYZ_FS {
            0 => 2,
            1 => 4,
            _ => 8,
        }
    }

    /// Whether the chip is sampling.
    pub const fn active(&self) -> bool {
        self.regs[nxp::CTRL_REG1 as usize] & nxp::CTRL1_ACTIVE != 0
    }

    /// The sample period in force, µs.
    pub const fn period_us(&self) -> u64 {
        const PERIODS: [u64; 8] = [
            1_250, 2_500, 5_000, 10_000, 20_000, 80_000, 160_000, 640_000,
        ];
        PERIODS[((self.regs[nxp::CTRL_REG1 as usize] & nxp::CTRL1_DR) >> 3) as usize]
    }

    /// A register as stored (inspection, no side effects).
    pub fn register(&self, register: u8) -> u8 {
        if register == nxp::WHO_AM_I {
            return self.who_am_i();
        }
        self.regs.get(usize::from(register)).copied().unwrap_or(0)
    }

    /// Samples latched since power-on.
    pub const fn latched(&self) -> u32 {
        self.latched
    }

    /// Back to the power-on state (the clock and the tilt are kept).
    pub(crate) fn power_on_reset(&mut self) {
        self.regs = [0; REGISTERS];
        self.pointer = 0;
        self.msb_read = 0;
        self.flush_fifo();
    }

    /// Whether a soft reset is still in progress (nothing is acknowledged).
    pub const fn resetting(&self) -> bool {
        self.now_us < self.resetting_until_us
    }

    /// Whether the FIFO is on (FXOS8700CQ, `F_MODE` non-zero).
    pub const fn fifo_on(&self) -> bool {
        self.regs[nxp::F_SETUP as usize] & nxp::F_MODE != 0
    }

    /// Samples waiting in the FIFO.
    pub const fn fifo_len(&self) -> usize {
        self.fifo_len
    }

    fn flush_fifo(&mut self) {
        self.fifo_len = 0;
        self.fifo_overflow = false;
    }

    /// The sample just latched into the FIFO, by `F_MODE`.
    fn push_fifo(&mut self) {
        let mut sample = [0u8; 6];
        sample.copy_from_slice(&self.regs[1..7]);
        if self.fifo_len == FIFO_DEPTH {
            self.fifo_overflow = true;
            // Fill mode (0b10) stops at full; the others drop the oldest.
            if self.regs[nxp::F_SETUP as usize] & nxp::F_MODE == 0x80 {
                return;
            }
            self.fifo.copy_within(1.., 0);
            self.fifo_len -= 1;
        }
        self.fifo[self.fifo_len] = sample;
        self.fifo_len += 1;
    }

    fn f_status(&self) -> u8 {
        (u8::from(self.fifo_overflow) << 7) | self.fifo_len as u8
    }

    /// Sets the tilt (a board-frame reading) the next samples take.
    pub(crate) fn set_tilt(&mut self, tilt: AccelMg) {
        self.tilt = tilt;
    }

    /// Frozen (no new samples) or garbage (implausible samples).
    pub(crate) fn set_faults(&mut self, frozen: bool, garbage: bool) {
        self.frozen = frozen;
        self.garbage = garbage;
    }

    /// Runs the sampling clock to `now_us`: latches a sample when one is due.
    pub(crate) fn advance_to(&mut self, now_us: u64) {
        self.now_us = self.now_us.max(now_us);
        if !self.active() || self.now_us < self.next_due_us {
            return;
        }
        let period = self.period_us();
        let missed = (self.now_us - self.next_due_us) / period;
        self.next_due_us += (missed + 1) * period;
        if !self.frozen {
            self.latch();
            // The FIFO keeps every sample, not only the last (the tilt is
            // the same for all of them within one call).
            if self.fifo_on() {
                for _ in 0..missed.min(FIFO_DEPTH as u64) {
                    self.push_fifo();
                }
            }
        }
    }

    fn next_random(&mut self) -> u32 {
        // xorshift32: deterministic garbage.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x
    }

    fn latch(&mut self) {
        let bits = self.bits();
        let max = (1i32 << (bits - 1)) - 1;
        let min = -(1i32 << (bits - 1));
        // 2^(bits-1) counts span the full scale.
        let counts_per_g = (1i64 << (bits - 1)) / i64::from(self.full_scale_g());
        for (axis, &(board, sign)) in MOUNTING.iter().enumerate() {
            let counts = if self.garbage {
                let r = self.next_random();
                let magnitude = max - (r % (max as u32 / 10 + 1)) as i32;
                if r & 0x8000_0000 != 0 {
                    -magnitude
                } else {
                    magnitude
                }
            } else {
                let mg = i64::from(sign) * i64::from(self.tilt.to_array()[board]);
                let scaled = mg * counts_per_g;
                let rounded = if scaled >= 0 {
                    (scaled + 500) / 1000
                } else {
                    (scaled - 500) / 1000
                };
                rounded.clamp(i64::from(min), i64::from(max)) as i32
            };
            let [msb, lsb] = ((counts << (16 - bits)) as i16).to_be_bytes();
            let at = usize::from(nxp::OUT_X_MSB) + 2 * axis;
            self.regs[at] = msb;
            self.regs[at + 1] = lsb;
        }
        let status = &mut self.regs[nxp::STATUS as usize];
        let unread = *status & nxp::STATUS_ZYXDR != 0;
        *status = 0x0F | if unread { nxp::STATUS_ZYXOW | 0x70 } else { 0 };
        self.msb_read = 0;
        self.latched = self.latched.wrapping_add(1);
        if self.fifo_on() {
            self.push_fifo();
        }
    }

    /// An I²C write: sub-address, then data from there on. `false` when a
    /// data byte was not acknowledged (the FXOS8700CQ's `RST`): the bytes
    /// after it are not taken.
    pub(crate) fn i2c_write(&mut self, bytes: &[u8]) -> bool {
        let Some((&sub, data)) = bytes.split_first() else {
            return true;
        };
        self.pointer = sub & 0x7F;
        for &byte in data {
            if !self.write(self.pointer, byte) {
                return false;
            }
            self.pointer = (self.pointer + 1) & 0x7F;
        }
        true
    }

    /// An I²C read from the register pointer on.
    pub(crate) fn i2c_read(&mut self, buffer: &mut [u8]) {
        for byte in buffer.iter_mut() {
            *byte = self.read(self.pointer);
            self.pointer = (self.pointer + 1) & 0x7F;
        }
    }

    /// Writes one register; `false` when the byte is not acknowledged.
    fn write(&mut self, register: u8, value: u8) -> bool {
        let active = self.active();
        match register {
            nxp::CTRL_REG1 => {
                if active {
                    // Only standby may be selected while active.
                    self.regs[nxp::CTRL_REG1 as usize] = (self.regs[nxp::CTRL_REG1 as usize]
                        & !nxp::CTRL1_ACTIVE)
                        | (value & nxp::CTRL1_ACTIVE);
                } else {
                    self.regs[nxp::CTRL_REG1 as usize] = value;
                    if value & nxp::CTRL1_ACTIVE != 0 {
                        self.next_due_us = self.now_us + self.period_us();
                        self.flush_fifo();
                    }
                }
            }
            nxp::CTRL_REG2 if value & nxp::CTRL2_RST != 0 => {
                self.power_on_reset();
                self.resetting_until_us = self.now_us + RESET_US;
                return self.chip != Accelerometer::Fxos8700cq;
            }
            nxp::CTRL_REG2 | nxp::XYZ_DATA_CFG | CTRL_REG4 | CTRL_REG5 if !active => {
                self.regs[usize::from(register)] = value;
            }
            nxp::M_CTRL_REG1 | nxp::F_SETUP
                if !active && self.chip == Accelerometer::Fxos8700cq =>
            {
                self.regs[usize::from(register)] = value;
                if register == nxp::F_SETUP && value & nxp::F_MODE == 0 {
                    self.flush_fifo();
                }
            }
            // Read-only, reserved, or written while active: ignored.
            _ => {}
        }
        true
    }

    fn read(&mut self, register: u8) -> u8 {
        match register {
            nxp::WHO_AM_I => self.who_am_i(),
            nxp::STATUS if self.fifo_on() => self.f_status(),
            1..=6 if self.fifo_on() => {
                let value = self.fifo[0][usize::from(register - 1)];
                if register == 6 && self.fifo_len > 0 {
                    self.fifo.copy_within(1.., 0);
                    self.fifo_len -= 1;
                }
                if self.fifo_len == 0 {
                    self.fifo[0] = [0; 6];
                }
                value
            }
            1..=6 => {
                let value = self.regs[usize::from(register)];
                if register % 2 == 1 {
                    self.msb_read |= 1 << ((register - 1) / 2);
                    if self.msb_read == 0b111 {
                        self.regs[nxp::STATUS as usize] = 0;
                    }
                }
                value
            }
            r => self.regs.get(usize::from(r)).copied().unwrap_or(0),
        }
    }
}
