//! The MMA8653FC and the FXOS8700CQ on the v1's I²C bus, and the probe that
//! finds which accelerometer a board has.
//!
//! Hand-written, on the two chips' shared register map ([`super::accel::nxp`]):
//! no crate drives the FXOS8700CQ's accelerometer, and the MMA8653FC's
//! (`mma8x5x` 0.1.1) does not fit the v1's stack: it takes the blocking
//! embedded-hal 0.2 traits, while every board's input stack is async over
//! embedded-hal 1 (the one API the host tests drive, `input::lsm303` too),
//! and its typestate `Standby`/`Active` modes move the driver between types
//! at each re-initialisation. What the firmware needs of either chip is four
//! or five register writes and one seven-byte burst read.

use embedded_hal_async::i2c::I2c;

use super::accel::{identify, nxp, Accelerometer, NxpChip, PROBES};
use super::twi::TwiError;
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

/// (Re)configures `chip` ([`NxpChip::configuration`]): ±2 g, high
/// resolution, 200 Hz, active. Its identity is the probe's business: a
/// re-initialisation after a chip reset only has to write the registers
/// again. The first sample follows one sample period later (the
/// supervisor's not-ready tolerance covers it).
pub async fn configure<B: I2c<Error = TwiError>>(bus: &mut B, chip: &NxpChip) -> Result<(), Fault> {
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
