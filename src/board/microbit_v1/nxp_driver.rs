//! The MMA8653FC and the FXOS8700CQ on the v1's I²C bus, and the probe that
//! finds which accelerometer a board has.
//!
//! Hand-written, on the two chips' shared register map ([`super::accel::nxp`]):
//! no crate drives the FXOS8700CQ's accelerometer, and the MMA8653FC's
//! (`mma8x5x` 0.1.1) does not fit the v1's stack: it takes the blocking
//! embedded-hal 0.2 traits, while every board's input stack is async over
//! embedded-hal 1 (the one API the host tests drive, `input::lsm303` too),
//! and its typestate `Standby`/`Active` modes move the driver between types
//! at each re-initialisation. What the firmware needs of either chip is a
//! soft reset, four or five register writes and one seven-byte burst read.

use embedded_hal_async::i2c::I2c;

use super::accel::{identify, nxp, Accelerometer, NxpChip, PROBES};
use super::twi::{Pause, TwiError};
use crate::input::sensor::{AccelMg, Fault, Read};

/// Probes for each accelerometer a v1 may carry ([`PROBES`], in order): the
/// first that answers with its identity.
pub async fn probe<B: I2c<Error = TwiError>>(bus: &mut B) -> Option<Accelerometer> {
    for probe in PROBES.iter() {
        let mut id = [0u8];
        let read = bus
            .write_read(probe.address, &[probe.register], &mut id)
            .await
            .ok()
            .map(|()| id[0]);
        if let Some(chip) = identify(probe, read) {
            return Some(chip);
        }
    }
    None
}

/// (Re)configures `chip`: a soft reset (`CTRL_REG2` `RST`), the wait
/// after it ([`nxp::RESET_WAIT_US`]), then [`NxpChip::configuration`]: ±2 g,
/// high resolution, 200 Hz, active. The reset comes first because the chip
/// keeps its registers across a reflash or a watchdog reset of the nRF: a
/// register this driver never writes (the FXOS8700CQ's FIFO mode, which
/// turns register 0x00 into `F_STATUS`) would otherwise stay as an earlier
/// firmware left it. The reset write's own outcome is not checked: the
/// FXOS8700CQ resets at once and does not acknowledge the byte that asked
/// for it (as Linux's `mma8452` and Zephyr's `fxos8700` drivers note); a
/// chip that is not there fails the writes that follow. Its identity is
/// the probe's business. The first sample follows one sample period after
/// the last write (the supervisor's not-ready tolerance covers it).
pub async fn configure<B: I2c<Error = TwiError> + Pause>(
    bus: &mut B,
    chip: &NxpChip,
) -> Result<(), Fault> {
    let _ = bus
        .write(chip.address, &[nxp::CTRL_REG2, nxp::CTRL2_RST])
        .await;
    bus.pause_us(nxp::RESET_WAIT_US);
    for &(register, value) in chip.configuration() {
        bus.write(chip.address, &[register, value])
            .await
            .map_err(TwiError::fault)?;
    }
    Ok(())
}

/// One poll in the chip's frame, milli-g: the status and the three axes in
/// one burst (the register pointer auto-increments from `STATUS`).
pub async fn read<B: I2c<Error = TwiError>>(bus: &mut B, chip: &NxpChip) -> Read<AccelMg> {
    let mut burst = [0u8; nxp::BURST];
    match bus
        .write_read(chip.address, &[nxp::STATUS], &mut burst)
        .await
    {
        Err(e) => Read::Failed(e.fault()),
        Ok(()) => match chip.sample(&burst) {
            Some(sample) => Read::Sample(sample),
            None => Read::NotReady,
        },
    }
}
