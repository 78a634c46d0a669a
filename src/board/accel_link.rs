//! The accelerometer link of a micro:bit: the LSM303AGR on the internal I²C
//! bus, as the micro:bit v2 runs it. The QEMU board models the same link (its
//! virtual LSM303AGR sits as on the v2, behind a model of the v2's TWIM), so
//! that it runs the v2's input stack with the v2's numbers; a v1.5's
//! LSM303AGR sits the same way round ([`AXIS_MAP`]). Pure constants, so the
//! boards that share them import this module and not each other.

#[cfg(doc)]
use crate::input::accel_timing::ACCEL_ODR_HZ;
use crate::input::sensor::{Axis, AxisMap, AxisSource, SupervisorConfig};

/// Sensor and button polling period. 100 Hz: twice the game's step rate.
pub const INPUT_PERIOD_MS: u64 = 10;

/// Fault supervision tuned for [`INPUT_PERIOD_MS`] and [`ACCEL_ODR_HZ`]: a
/// sample is due every 5 ms and the poll comes every 10 ms, so a poll without
/// new data is timing (a poll squeezed after slow work, the first poll after a
/// re-init); three in a row, about 30 ms or six sample periods without a
/// sample, is [`Fault::NoData`](crate::input::event::Fault::NoData).
pub const SUPERVISOR: SupervisorConfig = SupervisorConfig {
    not_ready_before_fault: 3,
    ..SupervisorConfig::DEFAULT
};

/// Internal I²C bus clock, kHz (the TWIM's `K400`).
pub const I2C_KHZ: u32 = 400;

/// Longest transfer the accelerometer driver makes: a register address
/// written, six data bytes read back (the three axes) — in bits on the wire,
/// including both address bytes, the ACK bits and the START/repeated
/// START/STOP conditions.
pub const LONGEST_TRANSFER_BITS: u32 = (2 + 1 + 6) * 9 + 3;

/// Deadline of one I²C transfer, ms. The longest transfer lasts
/// [`LONGEST_TRANSFER_BITS`] / [`I2C_KHZ`] ≈ 0.2 ms and the LSM303AGR does not
/// stretch the clock, so a transfer still running after 5 ms (over 20× that,
/// more than one RTC tick of timer granularity, half a poll period) is a hung
/// bus, not a slow one.
pub const I2C_TIMEOUT_MS: u64 = 5;

/// Size of the TWIM's RAM copy buffer, bytes.
///
/// nRF EasyDMA reads only RAM. embassy-nrf's `Twim` (`twim.rs`,
/// `Twim::set_tx_buffer`) copies a write buffer that is not in RAM into this
/// buffer, and refuses the transfer with `Error::RAMBufferTooSmall` (no bus
/// traffic at all) when the buffer is shorter than the write. lsm303agr 1.1
/// (`interface.rs`, `I2cInterface::read_register` and friends) reads a
/// register with `write_read(address, &[R::ADDR], …)` (`&[R::ADDR | 0x80]`
/// for multi-byte reads): a constant slice, which Rust promotes to a
/// `'static` in flash. With no copy buffer, every read — WHO_AM_I first —
/// fails. The largest write any driver call makes is 2 bytes
/// (`write_accel_register`/`write_mag_register`: register address + value,
/// built on the stack, but the optimiser may fold such constants into flash
/// too), so 2 bytes cover every write wherever the compiler puts it.
///
/// The rule: every EasyDMA peripheral gets a copy buffer, sized for the
/// largest write its drivers make, unless every buffer it is given is
/// provably in RAM.
pub const TWIM_COPY_BUFFER_BYTES: usize = 2;

/// LSM303AGR axes → board frame (`x` right, `y` up out of the LEDs, `z`
/// towards the player, who holds the board with the logo away and the edge
/// connector near; a flat board reads (0, +1000, 0)).
///
/// **Assumption (not verified on hardware here):** taken from the micro:bit
/// runtime (CODAL, `LSM303Accelerometer.cpp` + `CoordinateSpace(SIMPLE_CARTESIAN,
/// upside-down, 0°)`), which turns the raw registers into the documented
/// micro:bit frame as `(x, y, z)ₘ = (raw_x, −raw_y, raw_z)`, where the micro:bit
/// frame reads +1000 on x with the B (right) edge down, +1000 on y with the
/// edge connector down, −1000 on z lying screen-up. Hence, with the chip on the
/// back: raw `x` reads +1 g with the right edge down, raw `y` +1 g with the
/// logo edge down, raw `z` +1 g lying screen-down. Independent raw readings
/// (the "micro:bit v2 book" for Rust) agree for y and z. In the board frame:
/// `x = −raw_x`, `y = −raw_z`, `z = +raw_y`.
///
/// If the marble rolls the wrong way along one axis on a real board, flip
/// that row's sign here; the host tests in `tests/microbit_axes.rs` state
/// the expected readings per orientation and must be updated with it.
pub const AXIS_MAP: AxisMap = AxisMap {
    x: AxisSource::neg(Axis::X),
    y: AxisSource::neg(Axis::Z),
    z: AxisSource::pos(Axis::Y),
};
