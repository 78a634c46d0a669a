//! The accelerometer's timing, as every board configures it: its output data
//! rate and how long its output takes to become valid after a mode change.
//!
//! The figures belong to the input path, not to a board: the LSM303AGR glue
//! ([`super::lsm303`], feature `lsm303agr`) configures the chip for them, the
//! micro:bit v1's NXP chip is set to the same rate, and each board's fault
//! supervision is tuned for them.

/// Accelerometer output data rate, Hz. Twice the boards' 100 Hz polling rate,
/// so a poll normally finds a fresh sample; one that does not is "not ready
/// yet", not a fault (see [`SupervisorConfig`](super::sensor::SupervisorConfig)).
pub const ACCEL_ODR_HZ: u32 = 200;

/// Time to wait after (re)configuring the accelerometer before trusting its
/// output: high-resolution mode needs 7 samples at [`ACCEL_ODR_HZ`] (35 ms).
pub const ACCEL_SETTLE_MS: u64 = 40;
